//! A camera's light-group intensities: the baked animation relit at runtime
//! (docs/pack-format.md, "Light groups"; `plenoptic_recon::relight` holds the math).
//!
//! A pack baked with `[[light_group]]`s stores each group's light apart. A camera sets a
//! colour × intensity per group by the group's name ([`LightSettings::set`]); groups it
//! does not set stay at 1, as baked. The app may change them every frame: on the GPU the
//! camera's resident keys are relit once per frame by a compute pass
//! (`reconstruct/geometry/relight.rs`), on the CPU by the reconstructor's relit chunks.

use bevy::prelude::*;
use plenoptic_pack::{DEFAULT_GROUP, GroupWeights, Manifest};
use plenoptic_recon::relight::Relight;

/// A colour × intensity per light group of a camera's pack, by group name (the recipe's
/// `[[light_group]]` names, and `default` for the emitters no group names).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LightSettings {
    settings: Vec<(String, Vec3)>,
}

impl LightSettings {
    /// Sets group `name` to colour × intensity `weight` (1: as baked, 0: off).
    pub fn set(&mut self, name: impl Into<String>, weight: Vec3) -> &mut Self {
        let name = name.into();
        match self.settings.iter_mut().find(|(n, _)| *n == name) {
            Some(s) => s.1 = weight,
            None => self.settings.push((name, weight)),
        }
        self
    }

    /// Group `name`'s colour × intensity (1 when it was never set).
    pub fn get(&self, name: &str) -> Vec3 {
        self.settings
            .iter()
            .find(|(n, _)| n == name)
            .map_or(Vec3::ONE, |s| s.1)
    }

    /// Whether every group is as baked.
    pub fn is_identity(&self) -> bool {
        self.settings.iter().all(|(_, w)| *w == Vec3::ONE)
    }

    /// The weights over `manifest`'s groups. A name the pack does not have is an error that
    /// lists its groups (a pack without groups has only `default`).
    pub fn weights(&self, manifest: &Manifest) -> Result<GroupWeights, String> {
        let names = manifest.light_groups.as_ref().map(|e| &e.names[..]);
        self.weights_over(names.unwrap_or_default())
    }

    /// The weights over groups `names` (the pack's declared groups, in order).
    fn weights_over(&self, names: &[String]) -> Result<GroupWeights, String> {
        GroupWeights::from_names(names, &self.settings)
    }

    /// What the weights give each emitter of `manifest`'s pack; as baked where a name is
    /// unknown (which [`LightSettings::weights`] reports).
    pub fn relight(&self, manifest: &Manifest) -> Relight {
        let weights = self.weights(manifest).unwrap_or_default();
        Relight::new(manifest, &weights)
    }
}

/// The name of the default group, for [`LightSettings::set`].
pub const DEFAULT_LIGHT_GROUP: &str = DEFAULT_GROUP;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_group_set_twice_keeps_its_last_weight_and_unset_groups_are_as_baked() {
        let mut s = LightSettings::default();
        assert!(s.is_identity());
        s.set("lamp", Vec3::ZERO).set("lamp", Vec3::splat(0.5));
        assert_eq!(s.get("lamp"), Vec3::splat(0.5));
        assert_eq!(s.get("sky"), Vec3::ONE);
        assert!(!s.is_identity());
    }

    #[test]
    fn an_unknown_group_is_an_error_naming_the_packs_groups() {
        let mut s = LightSettings::default();
        s.set("lamp", Vec3::ZERO);
        let e = s.weights_over(&[]).unwrap_err();
        assert!(e.contains("'lamp'") && e.contains(DEFAULT_GROUP), "{e}");
        s = LightSettings::default();
        s.set(DEFAULT_LIGHT_GROUP, Vec3::splat(2.0));
        assert_eq!(s.weights_over(&[]).unwrap().default, Vec3::splat(2.0));
        let w = s.weights_over(&["lamp".to_string()]).unwrap();
        assert_eq!(w.groups, vec![Vec3::ONE]);
    }
}
