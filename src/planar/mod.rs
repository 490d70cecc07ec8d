//! Planar polygons and their boolean operations.
