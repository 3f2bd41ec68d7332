//! limpid-analysis
