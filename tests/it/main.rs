//! The integration tests of mbfmu, in one crate: one module per area (the former
//! `tests/<area>.rs` files) and the helpers they share in `common` (engine-side) and
//! `common::host` (a host of the FMU's C API). One crate links the library once instead
//! of once per file. Select a module with a filter: `cargo test --release --test it
//! fmi_sequences::`, `cargo nextest run --release -E 'test(/^fmi_capi::/)'`.
//!
//! Only tests/memory_alloc.rs is a crate of its own: it counts the whole process's
//! allocations (its own global allocator), which the other tests' threads would disturb
//! under `cargo test`.

mod common;

mod algebraic_loop;
mod architecture;
mod assembly;
mod assembly_branches;
mod bicycle_benchmark;
mod block_lu;
mod bounded_step;
mod bushing;
mod chain_work;
mod cli;
mod cli_linearize;
mod cli_set;
mod cli_stats;
mod dependencies;
mod eigen_routes;
mod elements;
mod expr_derivatives;
mod flexible;
mod flexible_dynamics;
mod flexible_fmu;
mod fmi3_sequences;
mod fmi_capi;
mod fmi_layer;
mod fmi_sequences;
mod iteration_matrix;
mod jacobians;
mod linearize;
mod linearize_loads;
mod linearize_routes;
mod linearize_seed;
mod linearize_seeded;
mod malformed;
mod memory_valgrind;
mod modal;
mod model_description;
mod model_exchange;
mod models_parse;
mod modes;
mod nonholonomic;
mod pack;
mod physics;
mod physics_pendulum;
mod rank;
mod redundant;
mod sparse_solve;
mod state;
mod state_choice;
mod user_elements;
