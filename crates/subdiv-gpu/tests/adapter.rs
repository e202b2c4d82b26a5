//! The device: our own, or an application's wrapped by `Gpu::from_parts` (checked against the
//! required limits).

use subdiv_gpu::{Gpu, GpuError};

#[test]
fn a_device_or_a_reason() {
    let Some(gpu) = subdiv_testkit::gpu() else { return };
    assert!(!gpu.adapter_name().is_empty());
    assert!(gpu.limits().max_storage_buffer_binding_size >= 128 << 20);
    assert!(Gpu::required_limits().check_limits(gpu.limits()));
}

/// A device of the test's own on the adapter `Gpu::new` would take, with `limits`.
fn own_device(limits: wgpu::Limits) -> (wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .expect("an adapter (subdiv_testkit::gpu found one)");
    pollster::block_on(
        adapter.request_device(&wgpu::DeviceDescriptor { required_limits: limits, ..Default::default() }),
    )
    .expect("a device")
}

#[test]
fn an_applications_device_is_wrapped_when_it_meets_the_limits() {
    let Some(ours) = subdiv_testkit::gpu() else { return };
    // WebGPU's defaults are enough, and so is exactly what the crate asks for.
    for limits in [wgpu::Limits::default(), Gpu::required_limits()] {
        let (device, queue) = own_device(limits.clone());
        let gpu = Gpu::from_parts(device.clone(), queue).expect("the limits are met");
        assert_eq!(gpu.limits(), &device.limits());
        assert_eq!(gpu.adapter_name(), ours.adapter_name());
        assert_eq!(gpu.limits().max_storage_buffers_per_shader_stage, limits.max_storage_buffers_per_shader_stage);
    }
    // Downlevel devices bind 4 storage buffers per stage; WebGL2-like ones have no compute.
    for (limits, name) in [
        (wgpu::Limits::downlevel_defaults(), "max_storage_buffers_per_shader_stage"),
        (wgpu::Limits { max_compute_workgroup_size_x: 32, ..Gpu::required_limits() }, "max_compute_workgroup_size_x"),
    ] {
        let (device, queue) = own_device(limits);
        match Gpu::from_parts(device, queue) {
            Err(GpuError::Limit { limit, required, available, .. }) => {
                assert_eq!(limit, name);
                assert!(required > available, "{limit}: {required} against {available}");
            }
            other => panic!("expected a limit error for {name}, got {other:?}"),
        }
    }
}
