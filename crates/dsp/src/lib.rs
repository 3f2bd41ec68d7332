//! limpid-dsp
