//! plenoptic_bake (being written).

pub mod delaunay3;
