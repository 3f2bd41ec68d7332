//! limpid-lab
