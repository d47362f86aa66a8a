//! The temporal volume's lookup as the geometry-assisted fallback uses it
//! ([`VolumeIndex::lookup_pair`]).

use std::sync::Arc;

use glam::Vec3;
use plenoptic_pack::{VolumeBlock, VolumeSample};

use super::{BlockBins, VolumeIndex};
use crate::lookup::SAME_FACE_COS;
use crate::shading::Channel;

/// A sample of object 1 at 2 m straight ahead (+Z) of the view, at time 0, lit `light`,
/// whose surface faces `normal`.
fn sample(light: f32, normal: Vec3) -> VolumeSample {
    VolumeSample {
        direction: Vec3::Z,
        t: 0.0,
        radiance: Vec3::splat(light),
        lighting: Vec3::splat(light),
        non_diffuse: Vec3::ZERO,
        distance: 2.0,
        normal,
        object_id: 1,
        radius: 0.05,
    }
}

/// The two sides of a thin shell at one point (a lampshade's lamp-lit inside, facing the
/// view, and its dim outside, facing away), binned for lookups of the lighting at time 0.
fn shell() -> VolumeIndex {
    let block = VolumeBlock {
        t_start: 0.0,
        t_end: 1.0,
        samples: vec![sample(4.0, -Vec3::Z), sample(0.5, Vec3::Z)],
    };
    VolumeIndex {
        blocks: vec![Arc::new(BlockBins::new(Arc::new(block)))],
        channel: Channel::Lighting,
        t: 0.0,
        eps: 0.5,
    }
}

#[test]
fn a_surface_takes_only_the_samples_that_face_as_it_does() {
    let index = shell();
    let at = Vec3::Z * 2.0;
    let light = |normal: Vec3| {
        index
            .lookup_pair(at, 1, 0.03, None, normal)
            .map(|(c, _, _)| c.x)
    };
    // The inside (its normal towards the view) takes the inside's sample, the outside the
    // outside's.
    assert!((light(-Vec3::Z).unwrap() - 4.0).abs() < 1e-5);
    assert!((light(Vec3::Z).unwrap() - 0.5).abs() < 1e-5);
    // Within the face test's angle the sample still counts; past it, it does not (and the
    // other side's faces away).
    let tilt = |cos: f32| Vec3::new((1.0 - cos * cos).sqrt(), 0.0, -cos);
    assert!((light(tilt(SAME_FACE_COS + 0.01)).unwrap() - 4.0).abs() < 1e-5);
    assert_eq!(light(tilt(SAME_FACE_COS - 0.01)), None);
    // Without a normal both sides count, with equal weights.
    assert!((light(Vec3::ZERO).unwrap() - 2.25).abs() < 1e-5);
}

#[test]
fn a_surface_no_sample_faces_gets_no_answer() {
    let index = shell();
    // A surface at right angles to both sides (a rim): neither sample is its face.
    assert!(
        index
            .lookup_pair(Vec3::Z * 2.0, 1, 0.03, None, Vec3::X)
            .is_none()
    );
}
