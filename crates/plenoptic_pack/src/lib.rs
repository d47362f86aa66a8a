//! plenoptic_pack (being written).
