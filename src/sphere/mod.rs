//! Spherical polygons.
