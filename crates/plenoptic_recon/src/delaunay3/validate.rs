//! Exhaustive validity check of a tetrahedralization (tests and debugging).

use super::{FACE, NO_NEIGHBOUR, Tetrahedralization, insphere, orient};

/// Checks that `tri` is a Delaunay tetrahedralization of `points` (for tests and debugging:
/// O(tetrahedra × points) exact `insphere` tests, so keep inputs small):
///
/// * indices in range, every tetrahedron positively oriented (exact `orient3d`);
/// * each face shared by at most two tetrahedra, lying on opposite sides of it, and
///   `neighbours` (when present) consistent with that; every boundary face a convex-hull facet
///   (no input point strictly outside it);
/// * the complex is a ball: V − E + F − T = 1;
/// * every non-skipped point is a vertex, no skipped point is, and each skipped point equals
///   its `duplicate_of`;
/// * empty circumspheres: no input point strictly inside any tetrahedron's circumsphere.
pub fn validate(tri: &Tetrahedralization, points: &[[f64; 3]]) -> Result<(), String> {
    let p = |i: u32| points[i as usize];
    let nt = tri.tets.len();
    if !tri.neighbours.is_empty() && tri.neighbours.len() != nt {
        return Err(format!(
            "{} neighbour rows for {nt} tets",
            tri.neighbours.len()
        ));
    }
    let mut used = vec![false; points.len()];
    for (t, v) in tri.tets.iter().enumerate() {
        for &i in v {
            if i as usize >= points.len() {
                return Err(format!("tet {t} names point {i} of {}", points.len()));
            }
            used[i as usize] = true;
        }
        if orient(p(v[0]), p(v[1]), p(v[2]), p(v[3])) <= 0.0 {
            return Err(format!("tet {t} {v:?} is not positively oriented"));
        }
    }
    if tri.skipped.len() != tri.duplicate_of.len() {
        return Err("skipped and duplicate_of differ in length".into());
    }
    let mut skipped = vec![false; points.len()];
    for (&s, &d) in tri.skipped.iter().zip(&tri.duplicate_of) {
        if s as usize >= points.len() || d as usize >= points.len() || p(s) != p(d) {
            return Err(format!("skipped point {s} does not duplicate {d}"));
        }
        skipped[s as usize] = true;
    }
    for i in 0..points.len() {
        if used[i] == skipped[i] {
            return Err(format!(
                "point {i}: used {} skipped {}",
                used[i], skipped[i]
            ));
        }
    }
    // Faces.
    let mut faces: Vec<([u32; 3], u32, u8)> = Vec::with_capacity(4 * nt);
    for (t, v) in tri.tets.iter().enumerate() {
        for (i, face) in FACE.iter().enumerate() {
            let mut f = face.map(|k| v[k]);
            f.sort_unstable();
            faces.push((f, t as u32, i as u8));
        }
    }
    faces.sort_unstable();
    let mut nfaces = 0usize;
    let mut k = 0;
    while k < faces.len() {
        nfaces += 1;
        let (f, t, i) = faces[k];
        let v = tri.tets[t as usize];
        let oriented = FACE[i as usize].map(|j| p(v[j]));
        if k + 1 < faces.len() && faces[k + 1].0 == f {
            if k + 2 < faces.len() && faces[k + 2].0 == f {
                return Err(format!("face {f:?} is shared by more than two tets"));
            }
            let (_, t2, i2) = faces[k + 1];
            let other = p(tri.tets[t2 as usize][i2 as usize]);
            if orient(oriented[0], oriented[1], oriented[2], other) >= 0.0 {
                return Err(format!("tets {t} and {t2} overlap across face {f:?}"));
            }
            if !tri.neighbours.is_empty()
                && (tri.neighbours[t as usize][i as usize] != t2
                    || tri.neighbours[t2 as usize][i2 as usize] != t)
            {
                return Err(format!("neighbours of tets {t}, {t2} inconsistent"));
            }
            k += 2;
        } else {
            if !tri.neighbours.is_empty() && tri.neighbours[t as usize][i as usize] != NO_NEIGHBOUR
            {
                return Err(format!("hull face {f:?} of tet {t} has a neighbour"));
            }
            // Hull facet: the tet is on its positive side, so nothing may be on the negative.
            if let Some(q) = (0..points.len() as u32)
                .find(|&q| orient(oriented[0], oriented[1], oriented[2], p(q)) < 0.0)
            {
                return Err(format!("point {q} lies outside boundary face {f:?}"));
            }
            k += 1;
        }
    }
    // Euler characteristic of a ball.
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(6 * nt);
    for v in &tri.tets {
        for a in 0..4 {
            for b in a + 1..4 {
                edges.push((v[a].min(v[b]), v[a].max(v[b])));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let nv = used.iter().filter(|&&u| u).count() as i64;
    let chi = nv - edges.len() as i64 + nfaces as i64 - nt as i64;
    if chi != 1 {
        return Err(format!("Euler characteristic {chi}, expected 1"));
    }
    // Empty circumspheres.
    for (t, v) in tri.tets.iter().enumerate() {
        let [a, b, c, d] = v.map(p);
        if let Some(q) = (0..points.len()).find(|&q| insphere(a, b, c, d, points[q]) > 0.0) {
            return Err(format!(
                "point {q} is inside the circumsphere of tet {t} {v:?}"
            ));
        }
    }
    Ok(())
}
