//! plenoptic_recon (being written).
