//! drape's criterion benches live in `benches/` (see `benches/kernels.rs`);
//! this library only gives the bench crate a target and is empty.
