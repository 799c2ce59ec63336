//! Oscillatory Hankel-type quadrature (written in the project: no crate does it).
