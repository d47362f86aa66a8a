//! Temporal reconstruction between time keys (thesis appendix A.1, "linear form curves").
//!
//! Each pixel's value over the keys is a piecewise cubic Bézier curve through the key values
//! `p_i` at key times `a_i`. Segment `[a_i, a_{i+1}]` has control points
//! `p_i, p_i⁺, p_{i+1}⁻, p_{i+1}`, evaluated by de Casteljau's nested `line(bary(t))` of A.1.
//! The interior points follow the thesis's construction from the chords on either side of a
//! key, written for non-uniform key spacing:
//!
//! `m_i = (p_{i+1} − p_{i−1}) / (a_{i+1} − a_{i−1})`,
//! `p_i⁺ = p_i + m_i (a_{i+1} − a_i)/3`, `p_i⁻ = p_i − m_i (a_i − a_{i−1})/3`,
//!
//! which for uniform spacing is `p_i ± (p_{i+1} − p_{i−1})/6`. (The thesis's printed
//! coefficient, ⅓ on each chord, is twice that and does not reproduce linear data; with ½ of
//! it a linear sequence stays linear and the curve is C¹.) At the ends, the tangent is the one
//! chord: `m_0 = (p_1 − p_0)/(a_1 − a_0)`. With two keys the curve is the straight line.
//!
//! The curve is linear in the key values, so it is computed once per frame as weights over at
//! most four keys ([`bezier_weights`]) and applied to whole cubes ([`blend_cubes`]).

use glam::Vec3;
use plenoptic_pack::CubeImage;

/// Weights `(key index, weight)` (at most four, summing to 1) such that the Bézier curve
/// through values at `times` equals `Σ weight · value[key]` at time `t` (clamped to the keys'
/// range). Empty for no keys. `times` must be increasing.
pub fn bezier_weights(times: &[f32], t: f32) -> Vec<(usize, f32)> {
    let n = times.len();
    if n == 0 {
        return Vec::new();
    }
    if n == 1 || !t.is_finite() || t <= times[0] {
        return vec![(0, 1.0)];
    }
    if t >= times[n - 1] {
        return vec![(n - 1, 1.0)];
    }
    let i = times
        .partition_point(|&a| a <= t)
        .saturating_sub(1)
        .min(n - 2);
    let (a0, a1) = (times[i], times[i + 1]);
    let h = a1 - a0;
    if h <= 0.0 {
        return vec![(i + 1, 1.0)];
    }
    let s = ((t - a0) / h).clamp(0.0, 1.0);
    // Coefficients over keys i-1, i, i+1, i+2 (slots 0..4).
    let mut w = [0.0f32; 4];
    // Tangent (per unit time) at key k as coefficients over the slots.
    let tangent = |k: usize| -> [f32; 4] {
        let mut c = [0.0f32; 4];
        let slot = |key: usize| key + 1 - i;
        let (lo, hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
        let dt = times[hi] - times[lo];
        if dt > 0.0 {
            c[slot(hi)] += 1.0 / dt;
            c[slot(lo)] -= 1.0 / dt;
        }
        c
    };
    let (m0, m1) = (tangent(i), tangent(i + 1));
    let b = [
        (1.0 - s).powi(3),
        3.0 * (1.0 - s).powi(2) * s,
        3.0 * (1.0 - s) * s * s,
        s.powi(3),
    ];
    // p_i
    w[1] += b[0] + b[1];
    // p_i⁺ = p_i + m_i h/3
    for (wk, mk) in w.iter_mut().zip(m0) {
        *wk += b[1] * mk * h / 3.0;
    }
    // p_{i+1}⁻ = p_{i+1} − m_{i+1} h/3
    w[2] += b[2] + b[3];
    for (wk, mk) in w.iter_mut().zip(m1) {
        *wk -= b[2] * mk * h / 3.0;
    }
    (0..4)
        .filter(|&k| w[k] != 0.0 && k + i >= 1 && k + i - 1 < n)
        .map(|k| (k + i - 1, w[k]))
        .collect()
}

/// The key at or nearest to `t`.
pub fn nearest_key(times: &[f32], t: f32) -> Option<usize> {
    (0..times.len()).min_by(|&a, &b| (times[a] - t).abs().total_cmp(&(times[b] - t).abs()))
}

/// The keys bracketing `t` and the linear weight of the second: `(k0, k1, s)` with
/// `t ≈ (1−s)·a_{k0} + s·a_{k1}`; outside the range both are the end key.
pub fn bracketing(times: &[f32], t: f32) -> Option<(usize, usize, f32)> {
    let n = times.len();
    if n == 0 {
        return None;
    }
    if n == 1 || t.is_nan() || t <= times[0] {
        return Some((0, 0, 0.0));
    }
    if t >= times[n - 1] {
        return Some((n - 1, n - 1, 0.0));
    }
    let i = times
        .partition_point(|&a| a <= t)
        .saturating_sub(1)
        .min(n - 2);
    let h = times[i + 1] - times[i];
    let s = if h > 0.0 {
        ((t - times[i]) / h).clamp(0.0, 1.0)
    } else {
        1.0
    };
    Some((i, i + 1, s))
}

/// The keys bracketing `t` that weigh anything, with their linear weights ([`bracketing`]):
/// one key at or outside the ends, else the two around `t`.
pub fn key_weights(times: &[f32], t: f32) -> Vec<(usize, f32)> {
    match bracketing(times, t) {
        None => Vec::new(),
        Some((k0, k1, _)) if k0 == k1 => vec![(k0, 1.0)],
        Some((k0, k1, s)) => [(k0, 1.0 - s), (k1, s)]
            .into_iter()
            .filter(|&(_, w)| w > 0.0)
            .collect(),
    }
}

/// Texel-wise weighted sum of radiance cubes (all of one face size), clamped to ≥ 0 (the
/// cubic may overshoot). `None` if the list is empty or the sizes differ.
pub fn blend_cubes(cubes: &[(&CubeImage<Vec3>, f32)]) -> Option<CubeImage<Vec3>> {
    let (first, _) = cubes.first()?;
    if cubes
        .iter()
        .any(|(c, _)| c.texels.len() != first.texels.len())
    {
        return None;
    }
    let mut out = vec![Vec3::ZERO; first.texels.len()];
    for (c, w) in cubes {
        for (o, v) in out.iter_mut().zip(&c.texels) {
            *o += *v * *w;
        }
    }
    for o in &mut out {
        *o = o.max(Vec3::ZERO);
    }
    Some(CubeImage {
        face_size: first.face_size,
        texels: out,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One key at or beyond the ends, the two around t inside, a key of zero weight left out.
    #[test]
    fn key_weights_are_the_bracketing_keys_that_weigh() {
        let times = [0.0, 1.0, 2.0];
        assert_eq!(key_weights(&times, -1.0), vec![(0, 1.0)]);
        assert_eq!(key_weights(&times, 5.0), vec![(2, 1.0)]);
        assert_eq!(key_weights(&times, 1.25), vec![(1, 0.75), (2, 0.25)]);
        assert_eq!(key_weights(&times, 1.0), vec![(1, 1.0)]);
        assert!(key_weights(&[], 1.0).is_empty());
    }

    fn eval(times: &[f32], values: &[f32], t: f32) -> f32 {
        bezier_weights(times, t)
            .iter()
            .map(|&(k, w)| w * values[k])
            .sum()
    }

    #[test]
    fn interpolates_keys_and_reproduces_lines() {
        let times = [0.0, 0.5, 1.5, 2.0, 3.0];
        let values = [1.0, 2.0, -1.0, 4.0, 0.5];
        for (a, v) in times.iter().zip(values) {
            assert!((eval(&times, &values, *a) - v).abs() < 1e-5);
        }
        let line: Vec<f32> = times.iter().map(|a| 2.0 * a + 1.0).collect();
        for k in 0..=30 {
            let t = k as f32 * 0.1;
            assert!(
                (eval(&times, &line, t) - (2.0 * t + 1.0)).abs() < 1e-4,
                "t = {t}"
            );
            let sum: f32 = bezier_weights(&times, t).iter().map(|w| w.1).sum();
            assert!((sum - 1.0).abs() < 1e-5);
        }
        assert_eq!(bezier_weights(&[1.0], 5.0), vec![(0, 1.0)]);
        assert!((eval(&[0.0, 1.0], &[0.0, 2.0], 0.25) - 0.5).abs() < 1e-6);
    }
}
