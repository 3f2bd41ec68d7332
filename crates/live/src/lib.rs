//! limpid-live: the live session of seed 001 Fig. 3 — a co-contraction bar fed
//! from the lab's acquisition system over UDP (or a replayed recording), with
//! an online stiffness estimate, served as a web page (axum, WebSocket).

#![warn(missing_docs)]

pub mod process;
pub mod server;
pub mod wire;
