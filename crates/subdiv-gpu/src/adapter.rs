//! The device: one of our own ([`Gpu::new`]: the library, the CLI, the tests) or an
//! application's ([`Gpu::from_parts`]).

use crate::GpuError;

/// How [`Gpu::new`] chooses the adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Prefer a low-power adapter (an integrated GPU) over a discrete one. Default: `false`.
    pub low_power: bool,
}

/// A device and its queue, with the adapter's description and the device's limits.
///
/// Made by [`Gpu::new`] (an adapter and a device of its own) or by [`Gpu::from_parts`] around
/// an application's device and queue. wgpu's `Device` and `Queue` are reference-counted
/// handles, so an application wraps clones and keeps using its own: a [`GpuTessellation`]
/// records into the application's encoders
/// ([`GpuTessellation::record`](crate::GpuTessellation::record)) and its buffers belong to
/// the application's device.
///
/// [`GpuTessellation`]: crate::GpuTessellation
#[derive(Debug)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
}

impl Gpu {
    /// A device on the best adapter found, on any backend wgpu was built with (Vulkan, Metal,
    /// DX12, GL; Mesa's lavapipe on Linux machines without a GPU), with the adapter's own
    /// limits (stencil data and vertex buffers can be large).
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when there is none, [`GpuError::Device`] when it refuses a
    /// device, [`GpuError::Limit`] when its limits are below [`Gpu::required_limits`].
    pub fn new(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let power_preference =
            if options.low_power { wgpu::PowerPreference::LowPower } else { wgpu::PowerPreference::HighPerformance };
        let adapter = pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions { power_preference, ..Default::default() }),
        )
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        // Before asking for a device: an adapter below the requirements is named as such.
        check_limits(&info, &limits)?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("subdiv"),
            required_limits: limits,
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device { adapter: info.name.clone(), reason: e.to_string() })?;
        Self::from_parts(device, queue)
    }

    /// Wraps an application's device and its queue (a wgpu or Bevy application's own), after
    /// checking that the device's limits meet [`Gpu::required_limits`]; no optional
    /// [`wgpu::Features`] are needed. The adapter's description comes from the device.
    ///
    /// ```no_run
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let instance = wgpu::Instance::default();
    /// let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    /// let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
    ///     // At least `Gpu::required_limits()`; the adapter's own let large meshes fit.
    ///     required_limits: adapter.limits(),
    ///     ..Default::default()
    /// }))?;
    /// // The handles are clones: the application keeps `device` and `queue`.
    /// let gpu = subdiv_gpu::Gpu::from_parts(device.clone(), queue.clone())?;
    /// # Ok(())
    /// # }
    /// ```
    ///
    /// # Errors
    /// [`GpuError::Limit`] naming the first limit below the requirement (e.g. a device made
    /// with [`wgpu::Limits::downlevel_defaults`], which has 4 storage buffers per shader
    /// stage where the evaluation binds 8, or without compute shaders).
    pub fn from_parts(device: wgpu::Device, queue: wgpu::Queue) -> Result<Self, GpuError> {
        let info = device.adapter_info();
        let limits = device.limits();
        check_limits(&info, &limits)?;
        Ok(Self { device, queue, info, limits })
    }

    /// The limits every part of this crate works within: WebGPU's downlevel defaults
    /// ([`wgpu::Limits::downlevel_defaults`], compute shaders included) with 8 storage buffers
    /// per shader stage (the evaluation's control points, entries, three kinds of records,
    /// patches, weights and vertices). Larger `max_storage_buffer_binding_size` and
    /// `max_buffer_size` let larger tessellations fit, and larger
    /// `max_texture_dimension_2d` larger images.
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits { max_storage_buffers_per_shader_stage: 8, ..wgpu::Limits::downlevel_defaults() }
    }

    /// The adapter's name and backend, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// The adapter's description.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The device's limits.
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }
}

/// [`GpuError::Limit`] for the first of `limits` below [`Gpu::required_limits`].
fn check_limits(info: &wgpu::AdapterInfo, limits: &wgpu::Limits) -> Result<(), GpuError> {
    let mut first = None;
    Gpu::required_limits().check_limits_with_fail_fn(limits, true, |limit, required, available| {
        first = Some(GpuError::Limit { adapter: info.name.clone(), limit, required, available });
    });
    first.map_or(Ok(()), Err)
}
