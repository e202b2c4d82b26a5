//! GPU evaluation of subdivision-surface tessellations, and offscreen rendering (wgpu).
//!
//! [`Gpu`] holds a device and its queue: one of its own ([`Gpu::new`], any backend wgpu was
//! built with: Vulkan, Metal, DX12, GL) or an application's ([`Gpu::from_parts`], checked
//! against [`Gpu::required_limits`]). A [`GpuTessellation`] uploads a CPU tessellation's
//! [`EvaluationPlan`](subdiv_tess::EvaluationPlan) and triangles; each frame, new control
//! points go in with `queue.write_buffer` ([`GpuTessellation::write_control_points`]) and the
//! evaluation is recorded into the application's encoder ([`GpuTessellation::record`]) ahead of
//! its render pass, which draws [`GpuTessellation::vertex_buffer`] as it is.
//! [`GpuTessellation::update_control_points`] does both and submits, for programs without an
//! encoder of their own. [`Renderer`] draws offscreen into an [`Image`] (RGBA8); the `png`
//! feature adds PNG encoding through the `image` crate.
//!
//! `examples/own_device.rs` is the whole path in an application's own device, encoder and
//! submission, checked against the CPU.

mod adapter;
mod error;
mod evaluate;
mod render;
mod scene;

pub use adapter::{Gpu, GpuOptions};
pub use error::GpuError;
pub use evaluate::{GpuEvalOptions, GpuTessellation, RateCache};
pub use render::{
    CAGE_VERTEX_STRIDE, GpuTexture, Image, MAX_CHECKER, MAX_IMAGE_SIDE, RenderOptions, Renderer, TEXCOORD_STRIDE,
    Texture, TextureImage, VERTEX_STRIDE,
};
pub use scene::{Cage, GpuCage, GpuMesh, GpuTexcoords, Lines, Scene, View, bounds, unique_edges};
