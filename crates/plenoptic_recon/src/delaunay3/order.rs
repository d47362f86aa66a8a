//! Insertion order: BRIO rounds sorted along a 3D Hilbert curve.

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Index along a 3D Hilbert curve of `bits` bits per axis (Skilling's transpose algorithm).
fn hilbert3(mut x: [u32; 3], bits: u32) -> u64 {
    let m = 1u32 << (bits - 1);
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    x[1] ^= x[0];
    x[2] ^= x[1];
    let mut t = 0;
    let mut q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for v in &mut x {
        *v ^= t;
    }
    let mut h = 0u64;
    for b in (0..bits).rev() {
        for v in x {
            h = (h << 1) | ((v >> b) & 1) as u64;
        }
    }
    h
}

/// BRIO: shuffle, cut into rounds of doubling size (the last holds half the points), sort each
/// round along a Hilbert curve.
pub(super) fn insertion_order(points: &[[f64; 3]], ids: &mut [u32]) {
    const BITS: u32 = 21;
    if ids.is_empty() {
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in ids.iter() {
        let p = points[i as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let scale = ((1u64 << BITS) - 1) as f64;
    let key = |i: u32| {
        let p = points[i as usize];
        let q = std::array::from_fn(|k| {
            let ext = hi[k] - lo[k];
            if ext > 0.0 && ext.is_finite() {
                (((p[k] - lo[k]) / ext).clamp(0.0, 1.0) * scale) as u32
            } else {
                0
            }
        });
        hilbert3(q, BITS)
    };
    let mut state = 0x005E_ED0F_DE1A_u64;
    for i in (1..ids.len()).rev() {
        let j = (splitmix(&mut state) % (i as u64 + 1)) as usize;
        ids.swap(i, j);
    }
    let mut end = ids.len();
    while end > 0 {
        let start = if end > 2000 { end / 2 } else { 0 };
        ids[start..end].sort_by_cached_key(|&i| (key(i), i));
        end = start;
    }
}
