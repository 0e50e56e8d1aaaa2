//! MCML compatibility: read MCML input files (`.mci`) and write MCML's output format
//! (`.mco`, version 1.2.2 layout, Wang, Jacques & Zheng 1995), so the baker can stand in for
//! MCML in existing scripts. MCML works in cm; the engine in mm.
//!
//! [`mci`] parses the input, [`grid`] scores MCML's 2D tallies alongside the engine's, [`mco`]
//! writes them with C's number formats (`printf`).

pub mod grid;
pub mod mci;
pub mod mco;
mod printf;

pub use grid::{simulate_grid, McmlGrid};
pub use mci::{parse_mci, McmlRun, MAX_GRID_CELLS};
pub use mco::write_mco;
