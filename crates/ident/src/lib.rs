//! limpid-ident
