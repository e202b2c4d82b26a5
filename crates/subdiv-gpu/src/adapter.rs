//! One way to get a device, shared by the library, the CLI and every GPU test.

use crate::GpuError;

/// How to choose the adapter.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Prefer a low-power adapter (an integrated GPU) over a discrete one.
    pub low_power: bool,
}

/// A device and its queue, with the adapter's description.
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
    /// A device on the best adapter found (any backend wgpu was built with: Vulkan here, which
    /// includes Mesa's lavapipe on machines without a GPU).
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when there is none, [`GpuError::Device`] when it refuses a device.
    pub fn new(options: &GpuOptions) -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let power_preference =
            if options.low_power { wgpu::PowerPreference::LowPower } else { wgpu::PowerPreference::HighPerformance };
        let adapter = pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions { power_preference, ..Default::default() }),
        )
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        // The adapter's own limits: stencil tables and vertex buffers can be large.
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("subdiv"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device { adapter: info.name.clone(), reason: e.to_string() })?;
        Ok(Self { device, queue, info, limits })
    }

    /// The device for a test: `None` (after saying so on stderr) when there is no adapter,
    /// unless `SUBDIV_REQUIRE_GPU=1`, where it panics instead, so that CI cannot pass by
    /// skipping.
    ///
    /// # Panics
    /// When no device can be had and `SUBDIV_REQUIRE_GPU=1`.
    #[allow(clippy::print_stderr)]
    pub fn for_tests() -> Option<Self> {
        match Self::new(&GpuOptions::default()) {
            Ok(gpu) => Some(gpu),
            Err(e) if std::env::var("SUBDIV_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
                panic!("SUBDIV_REQUIRE_GPU=1 but {e}")
            }
            Err(e) => {
                eprintln!("skipping a GPU test: {e}");
                None
            }
        }
    }

    /// The adapter's name and backend, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// The adapter's description.
    pub fn adapter_info(&self) -> &wgpu::AdapterInfo {
        &self.info
    }

    /// The device's limits (those of the adapter).
    pub fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_device_or_a_reason() {
        let Some(gpu) = Gpu::for_tests() else { return };
        assert!(!gpu.adapter_name().is_empty());
        assert!(gpu.limits().max_storage_buffer_binding_size >= 128 << 20);
    }
}
