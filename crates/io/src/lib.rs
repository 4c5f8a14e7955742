//! # drape-io
//!
//! drape's files. In: scene files (TOML) read into a [`drape_model::Model`]
//! and run settings, with errors that name the file, the line and the
//! field. Out: the results of a run — VTU frames and a PVD series for
//! ParaView, CSV tables (energy history, shear profiles), a JSON summary
//! and PNG pictures — each written whole or not at all.
//!
//! What it is not: no mechanics and no time loop.

pub mod atomic;
pub mod finite;
pub mod mesh_import;
pub mod results;
pub mod scene;
