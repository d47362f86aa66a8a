//! 3D Delaunay (being written).
