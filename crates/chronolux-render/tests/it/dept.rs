//! DEPT tests
