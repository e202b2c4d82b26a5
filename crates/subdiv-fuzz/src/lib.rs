//! Fuzzing subdiv's entry points on stable Rust: [`Target`]s (the OBJ and glTF readers, the
//! scheme-file parser, the rational-parameter parser, and the pipeline — build, refine,
//! tessellate, evaluate — on small random meshes), a [`driver`] that runs a target on mutations
//! of its seeds with a time limit per input, guided by edge [`coverage`] where the build is
//! instrumented (`cargo xtask fuzz --coverage`), and a [`reduce`]r that shrinks a failing input
//! to a minimal one, line by line and then byte by byte, as lyon's fuzzer shrinks its paths.
//!
//! A finding is a panic (an error is a correct answer to bad input), an error message of more
//! than one line, or a result that breaks the target's invariants (non-finite limit points,
//! triangles indexing past their vertices). `cargo xtask fuzz [--seconds N] [--target T]` runs
//! every target in a child process that also bounds time and memory, reduces what it finds and
//! keeps it under `crates/subdiv-fuzz/reproducers/<target>/`, which the crate's tests replay.
//!
//! ```
//! use subdiv_fuzz::Target;
//!
//! // Every seed of every target passes.
//! for target in Target::ALL {
//!     for seed in target.seeds() {
//!         target.run(&seed);
//!     }
//! }
//! ```

pub mod coverage;
pub mod driver;
pub mod reduce;
mod targets;

pub use targets::Target;
