//! The Kirchhoff-rod solver of Kmoch, Bonanni and Magnenat-Thalmann 2009 (after Bergou et al.
//! 2008): a Bishop frame, hair-optimised twist, symplectic Euler and a fast manifold projection.

pub mod step;
