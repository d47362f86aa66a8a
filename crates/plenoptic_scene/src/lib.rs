//! plenoptic_scene (being written).
