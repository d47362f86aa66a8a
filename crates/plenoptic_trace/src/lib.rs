//! plenoptic_trace (being written).
