//! limpid-io
