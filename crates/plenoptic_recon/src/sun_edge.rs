//! How much of a pixel a hard shadow edge leaves lit (the runtime sun's edge pixels,
//! [`crate::sun`]; docs/architecture.md, "The runtime sun").
//!
//! A sun without a disc casts a hard shadow, and within one pixel the shadow's edge is, to a
//! very good approximation, a straight line: the projection of an occluder's edge onto the
//! surface, which the pixel's footprint maps affinely. Estimating the lit fraction with `K`
//! scattered shadow rays leaves an error of order 1/K in every pixel the edge crosses, and
//! the path tracer's reference, whose jittered pixels average thousands of samples, shows
//! that error as a faint crawl along the edge.
//!
//! Here the line is found instead. The visibility is sampled at [`PERIMETER_SAMPLES`] points
//! around the pixel's square; where it changes between two neighbouring points, the change
//! is located by [`BISECTIONS`] halvings. Exactly two changes mean one edge crosses the
//! pixel: the lit part is the polygon cut off by the line through them, and its area is the
//! lit fraction (the map from the square to the footprint is affine, so fractions of area
//! carry over). This is the analytic coverage of a polygon edge that antialiasing by area
//! sampling computes for rasterised edges, found by searching for the edge instead of
//! knowing it. No change on the perimeter (the edge passes beside the pixel) means the pixel
//! is wholly lit or wholly shadowed, where its centre agrees. Anything else (a thin shadow's
//! four changes, a shadow smaller than the pixel) is left to the scattered rays. A shadow's
//! corner inside the pixel shows two changes and is measured as if cut straight between
//! them: off by at most the corner's triangle, in the few pixels that hold a corner.

use glam::Vec2;

/// Visibility samples around the pixel's perimeter, 4 on each side.
pub const PERIMETER_SAMPLES: usize = 16;

/// Halvings of the interval in which the visibility changes: a crossing is placed within
/// 1/(4 · 2⁷) of the pixel's side, so the lit fraction is exact to about 0.002.
pub const BISECTIONS: u32 = 7;

/// The lit fraction of the pixel's square `[-½, ½]²` when one straight edge crosses it, from
/// `open(uv)`: whether the sun reaches the point `uv` of the square; 0 or 1 where the
/// perimeter and the centre agree. `None` where the perimeter shows more than one edge, or
/// none but the centre differs (the caller then samples the pixel's area). Costs at most
/// [`PERIMETER_SAMPLES`] + 2 · [`BISECTIONS`] calls of `open`.
pub fn straight_edge_coverage(mut open: impl FnMut(Vec2) -> bool) -> Option<f32> {
    let n = PERIMETER_SAMPLES;
    let step = 4.0 / n as f32;
    let states: [bool; PERIMETER_SAMPLES] =
        std::array::from_fn(|i| open(perimeter(i as f32 * step)));
    // Where the sun comes in (shadow → lit, going round) and where it goes out.
    let (mut enters, mut leaves) = (None, None);
    for i in 0..n {
        let (a, b) = (states[i], states[(i + 1) % n]);
        if a == b {
            continue;
        }
        let slot = if b { &mut enters } else { &mut leaves };
        if slot.is_some() {
            return None;
        }
        let (mut lo, mut hi) = (i as f32 * step, (i + 1) as f32 * step);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if open(perimeter(mid)) == a {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        *slot = Some(0.5 * (lo + hi));
    }
    let (s_in, s_out) = match (enters, leaves) {
        (Some(s_in), Some(s_out)) => (s_in, s_out),
        // No change around the perimeter: the pixel is wholly lit or shadowed, unless its
        // centre says otherwise (a shadow smaller than the pixel).
        _ => return (open(Vec2::ZERO) == states[0]).then_some(f32::from(u8::from(states[0]))),
    };
    // The lit polygon: in along the perimeter (anticlockwise) past its corners to out, then
    // back along the edge.
    let s_end = if s_out > s_in { s_out } else { s_out + 4.0 };
    let mut polygon = [Vec2::ZERO; 6];
    let mut count = 0;
    polygon[count] = perimeter(s_in);
    count += 1;
    let mut corner = s_in.floor() + 1.0;
    while corner < s_end {
        polygon[count] = perimeter(corner % 4.0);
        count += 1;
        corner += 1.0;
    }
    polygon[count] = perimeter(s_end % 4.0);
    count += 1;
    Some(area(&polygon[..count]).clamp(0.0, 1.0))
}

/// The point at arc length `s` ∈ [0, 4) around the square `[-½, ½]²`, anticlockwise from
/// its corner (−½, −½).
fn perimeter(s: f32) -> Vec2 {
    let side = (s.floor() as i32).clamp(0, 3);
    let f = s - side as f32;
    match side {
        0 => Vec2::new(-0.5 + f, -0.5),
        1 => Vec2::new(0.5, -0.5 + f),
        2 => Vec2::new(0.5 - f, 0.5),
        _ => Vec2::new(-0.5, 0.5 - f),
    }
}

/// The area of a simple polygon (the shoelace formula).
fn area(polygon: &[Vec2]) -> f32 {
    let n = polygon.len();
    let twice: f32 = (0..n)
        .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
        .sum();
    0.5 * twice.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact lit fraction of the square on the side `n · uv < c` of a line, by dense
    /// sampling (1024² points: exact to about 1e-3 for any line).
    fn dense(n: Vec2, c: f32) -> f32 {
        let m = 1024;
        let mut lit = 0u32;
        for y in 0..m {
            for x in 0..m {
                let uv = Vec2::new((x as f32 + 0.5) / m as f32, (y as f32 + 0.5) / m as f32)
                    - Vec2::splat(0.5);
                lit += u32::from(n.dot(uv) < c);
            }
        }
        lit as f32 / (m * m) as f32
    }

    #[test]
    fn a_straight_edge_gives_the_lit_area() {
        let mut worst: f32 = 0.0;
        let mut found = 0;
        for k in 0..48 {
            // Lines at every angle, through the square at every offset.
            let angle = k as f32 * 0.37;
            let n = Vec2::from_angle(angle);
            for c in [-0.6, -0.45, -0.2, 0.0, 0.13, 0.31, 0.55] {
                let mut calls = 0;
                let got = straight_edge_coverage(|uv| {
                    calls += 1;
                    n.dot(uv) < c
                });
                assert!(calls <= PERIMETER_SAMPLES + 2 * BISECTIONS as usize);
                let want = dense(n, c);
                match got {
                    Some(f) => {
                        found += 1;
                        worst = worst.max((f - want).abs());
                    }
                    None => panic!("angle {angle}, offset {c}: {want} lit, not measured"),
                }
            }
        }
        assert!(found > 250, "{found}");
        assert!(worst < 0.004, "worst error {worst}");
    }

    #[test]
    fn no_edge_is_all_or_nothing_unless_the_centre_differs() {
        assert_eq!(straight_edge_coverage(|_| true), Some(1.0));
        assert_eq!(straight_edge_coverage(|_| false), Some(0.0));
        // A shadow inside the pixel, clear of its perimeter.
        assert_eq!(straight_edge_coverage(|uv| uv.length() > 0.2), None);
        // A thin shadow across the pixel: four changes around the perimeter.
        let stripe = straight_edge_coverage(|uv| uv.x.abs() > 0.1);
        assert_eq!(stripe, None);
    }
}
