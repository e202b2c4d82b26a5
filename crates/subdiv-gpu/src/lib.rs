//! GPU evaluation of subdivision-surface tessellations, and offscreen rendering (wgpu).
//!
//! [`Gpu`] holds a device and its queue. Every GPU test of the workspace gets one through
//! [`Gpu::for_tests`], which skips (saying so) when no adapter exists, unless
//! `SUBDIV_REQUIRE_GPU=1` is set, as `.ci/run` does: there a missing adapter fails the test.

mod adapter;
mod error;
mod evaluate;
mod render;

pub use adapter::{Gpu, GpuOptions};
pub use error::GpuError;
pub use evaluate::{GpuEvalOptions, GpuTessellation, RateCache};
pub use render::{
    CAGE_VERTEX_STRIDE, Cage, GpuCage, GpuMesh, Lines, MAX_IMAGE_SIDE, RenderOptions, Renderer, Scene, VERTEX_STRIDE,
    View, bounds, unique_edges,
};
