//! The working set: which (base view, time key) pairs a camera needs now and which it will
//! need soon. Pure functions over the manifest, unit-tested without a GPU.

use bevy::math::Vec3;
use plenoptic_pack::Manifest;
use plenoptic_recon::ReconSettings;

/// One streamable unit: the cubes (radiance, distance, object id, normal) of base view
/// `view` (index into the manifest's base views) at time key `key`.
pub type KeyRef = (u32, u32);

/// One temporal-volume block: (base view, time bucket).
pub type BlockRef = (u32, u32);

/// Indices of the `count` base views nearest `position`, nearest first.
pub fn nearest_views(manifest: &Manifest, position: Vec3, count: usize) -> Vec<u32> {
    let mut views: Vec<(f32, u32)> = manifest
        .base_views
        .iter()
        .enumerate()
        .map(|(i, v)| (v.position.distance_squared(position), i as u32))
        .collect();
    views.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    views.into_iter().take(count).map(|(_, i)| i).collect()
}

/// The time keys of `keys` bracketing `t`: the last key ≤ t and the first key ≥ t (one key
/// where t falls on a key or outside the keys).
pub fn bracketing_keys(keys: &[f32], t: f32) -> Vec<u32> {
    if keys.is_empty() {
        return Vec::new();
    }
    let after = keys.partition_point(|&k| k < t);
    if after < keys.len() && keys[after] == t {
        return vec![after as u32];
    }
    if after == 0 {
        return vec![0];
    }
    if after == keys.len() {
        return vec![keys.len() as u32 - 1];
    }
    vec![after as u32 - 1, after as u32]
}

/// What a camera needs, in priority order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WorkingSet {
    /// Needed for this frame: a frame without one of these stalls.
    pub needed: Vec<KeyRef>,
    /// Wanted soon (along the camera's motion and the playback direction); loaded only when
    /// the budget allows, never evicting needed data.
    pub prefetch: Vec<KeyRef>,
    /// Temporal-volume blocks of the needed base views around t (the GPU reconstruction's
    /// fallback where no time key sees a point); only those the pack has are read.
    pub volumes: Vec<BlockRef>,
    /// Volume blocks wanted soon, like [`WorkingSet::prefetch`].
    pub volume_prefetch: Vec<BlockRef>,
}

/// Parameters of [`working_set`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookahead<'a> {
    /// The camera's reconstruction settings: which base views it blends
    /// ([`ReconSettings::view_weights`]) and which volume buckets its window t ± tε reaches
    /// ([`ReconSettings::volume_buckets`]), as the reconstruction itself chooses them.
    pub settings: &'a ReconSettings,
    /// Seconds ahead to prefetch.
    pub seconds: f32,
}

/// The working set of a camera at `position` (base views limited to the `usable` ones) moving with `velocity` (m/s), at time `t`
/// playing in direction `direction` (seconds of animation per second).
pub fn working_set(
    manifest: &Manifest,
    usable: &[bool],
    position: Vec3,
    velocity: Vec3,
    t: f32,
    direction: f32,
    look: Lookahead<'_>,
) -> WorkingSet {
    let rs = look.settings;
    let mut set = WorkingSet::default();
    let push = |list: &mut Vec<KeyRef>, others: &[KeyRef], k: KeyRef| {
        if !list.contains(&k) && !others.contains(&k) {
            list.push(k);
        }
    };
    for (v, _) in rs.view_weights(manifest, usable, position) {
        let v = v as u32;
        for k in bracketing_keys(&manifest.base_views[v as usize].time_keys, t) {
            push(&mut set.needed, &[], (v, k));
        }
        for b in rs.volume_buckets(manifest, t) {
            set.volumes.push((v, b));
        }
    }
    let future_pos = position + velocity * look.seconds;
    let future_t = t + direction * look.seconds;
    for (v, _) in rs.view_weights(manifest, usable, future_pos) {
        let v = v as u32;
        let keys = &manifest.base_views[v as usize].time_keys;
        let mut ks = bracketing_keys(keys, t);
        ks.extend(bracketing_keys(keys, future_t));
        for k in ks {
            let needed = set.needed.clone();
            push(&mut set.prefetch, &needed, (v, k));
        }
        for b in rs
            .volume_buckets(manifest, t)
            .chain(rs.volume_buckets(manifest, future_t))
        {
            let volumes = set.volumes.clone();
            push(&mut set.volume_prefetch, &volumes, (v, b));
        }
    }
    set
}

#[cfg(test)]
mod tests {
    use super::*;
    use plenoptic_pack::{BaseView, TimeRange};

    fn manifest() -> Manifest {
        let mut m = Manifest::new(
            TimeRange {
                start: 0.0,
                end: 2.0,
            },
            0.5,
        );
        m.base_views = (0..5)
            .map(|i| BaseView {
                id: i,
                position: Vec3::new(i as f32, 0.0, 0.0),
                time_keys: vec![0.0, 1.0, 2.0],
            })
            .collect();
        m
    }

    #[test]
    fn brackets() {
        assert_eq!(bracketing_keys(&[0.0, 1.0, 2.0], 0.5), vec![0, 1]);
        assert_eq!(bracketing_keys(&[0.0, 1.0, 2.0], 1.0), vec![1]);
        assert_eq!(bracketing_keys(&[0.0, 1.0, 2.0], -1.0), vec![0]);
        assert_eq!(bracketing_keys(&[0.0, 1.0, 2.0], 3.0), vec![2]);
        assert!(bracketing_keys(&[], 3.0).is_empty());
    }

    #[test]
    fn needed_and_prefetch() {
        let m = manifest();
        let settings = ReconSettings {
            max_views: 2,
            ..ReconSettings::default()
        };
        let look = Lookahead {
            settings: &settings,
            seconds: 1.0,
        };
        let usable = [true; 5];
        let s = working_set(
            &m,
            &usable,
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::X * 3.0,
            0.5,
            1.0,
            look,
        );
        assert_eq!(s.needed, vec![(0, 0), (0, 1), (1, 0), (1, 1)]);
        // Moving +x at 3 m/s: views 3 and 4 (near x = 3.1) are prefetched, at t = 0.5 and 1.5.
        assert!(s.prefetch.contains(&(3, 1)) && s.prefetch.contains(&(3, 2)));
        assert!(s.prefetch.iter().all(|k| !s.needed.contains(k)));
        // Buckets of 0.5 s, tε = 0.25 s: t = 0.5 needs buckets 0 and 1 of both views.
        assert_eq!(s.volumes, vec![(0, 0), (0, 1), (1, 0), (1, 1)]);
        // At x = 3.1 and t = 1.5 (buckets 2 and 3) for views 3 and 4, and their buckets at t.
        assert!(s.volume_prefetch.contains(&(3, 3)) && s.volume_prefetch.contains(&(4, 0)));
        assert!(s.volume_prefetch.iter().all(|b| !s.volumes.contains(b)));
        assert_eq!(settings.volume_buckets(&m, 0.2), 0..=0);
        assert_eq!(settings.volume_buckets(&m, 0.8), 1..=2);
    }
}
