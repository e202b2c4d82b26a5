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
}
