//! Linearly transformed cosines and exact polygon integrals.
