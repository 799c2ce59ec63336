//! Heavy validation of lumest (see README).
