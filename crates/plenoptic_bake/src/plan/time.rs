//! Decomposing time (thesis §6.6.2 "view independent direct illumination coherence" and
//! §6.6.3 "view dependent temporal refinement"; docs/architecture.md, Baking step 5).
//!
//! Times live on a dyadic lattice of `2^max_time_depth` steps over the time range. An interval
//! is tested by comparing id-images rendered at its two ends; while the fitness is below q
//! (and the interval can still be halved) it is bisected. First the light pass: id-images
//! from every light ([`super::ids::light_ids`]); an interval passes when every light's pair
//! passes. Its keys seed every base view. Then each base view refines its own intervals with
//! cube id-images at its position. A static scene (nothing animated) has one key: the start.
//!
//! Because children are tested only where their parent failed and a larger q fails every
//! interval a smaller q failed, the keys for a larger q are a superset of those for a smaller
//! one.

use std::collections::BTreeMap;

/// Subdivides time on a lattice of `lattice` steps: starting from the sorted lattice keys
/// `seeds` (at least the two ends), every interval between consecutive keys is bisected while
/// `passes(a_value, b_value)` is false and it is longer than one step. `eval` computes the
/// value at a lattice key once. Returns the sorted keys, the number of intervals tested and
/// the values computed (one per key when there are two seeds or more).
pub fn subdivide<V>(
    seeds: &[u32],
    mut eval: impl FnMut(u32) -> V,
    mut passes: impl FnMut(&V, &V) -> bool,
) -> (Vec<u32>, u64, BTreeMap<u32, V>) {
    let mut values: BTreeMap<u32, V> = BTreeMap::new();
    let mut keys: Vec<u32> = seeds.to_vec();
    keys.sort_unstable();
    keys.dedup();
    let mut tested = 0u64;
    let mut stack: Vec<(u32, u32)> = keys.windows(2).rev().map(|w| (w[0], w[1])).collect();
    while let Some((a, b)) = stack.pop() {
        tested += 1;
        for k in [a, b] {
            values.entry(k).or_insert_with(|| eval(k));
        }
        if b - a <= 1 || passes(&values[&a], &values[&b]) {
            continue;
        }
        let m = a + (b - a) / 2;
        keys.push(m);
        stack.push((m, b));
        stack.push((a, m));
    }
    keys.sort_unstable();
    keys.dedup();
    (keys, tested, values)
}

/// The time of lattice key `k`.
pub fn key_time(start: f32, end: f32, lattice: u32, k: u32) -> f32 {
    if k == 0 || lattice == 0 {
        return start;
    }
    if k >= lattice {
        return end;
    }
    start + (end - start) * (k as f64 / lattice as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subdivides_only_where_values_differ() {
        // A step at lattice 5 of 16: only intervals containing it are split.
        let (keys, _, _) = subdivide(&[0, 16], |k| k >= 5, |a, b| a == b);
        assert_eq!(keys, vec![0, 4, 5, 6, 8, 16]);
        let (keys, _, _) = subdivide(&[0, 16], |_| 0, |a, b| a == b);
        assert_eq!(keys, vec![0, 16]);
    }

    #[test]
    fn key_times_hit_the_ends_exactly() {
        assert_eq!(key_time(0.5, 2.5, 8, 0), 0.5);
        assert_eq!(key_time(0.5, 2.5, 8, 8), 2.5);
        assert_eq!(key_time(0.0, 2.0, 8, 4), 1.0);
    }
}
