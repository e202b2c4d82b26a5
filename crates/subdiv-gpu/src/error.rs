/// What can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter (Vulkan driver) was found.
    #[error("no GPU adapter found (is a Vulkan driver installed? on Debian: mesa-vulkan-drivers): {0}")]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("the adapter {adapter} refused a device: {reason}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// wgpu's message.
        reason: String,
    },
    /// An image size outside what the renderer takes.
    #[error("image size {width}×{height}: each side must be from 1 to {max} pixels")]
    ImageSize {
        /// The width asked for.
        width: u32,
        /// The height asked for.
        height: u32,
        /// The largest side ([`MAX_IMAGE_SIDE`](crate::MAX_IMAGE_SIDE), or the device's texture
        /// limit if lower).
        max: u32,
    },
    /// A mesh or scene whose data or buffers do not hold what its counts say.
    #[error("{0}")]
    Scene(String),
    /// wgpu reported an error (validation, out of memory) during an operation.
    #[error("wgpu error while {during}: {message}")]
    Wgpu {
        /// What was being done.
        during: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// Reading a rendered image back from the device failed.
    #[error("reading the image back failed: {0}")]
    Readback(String),
}
