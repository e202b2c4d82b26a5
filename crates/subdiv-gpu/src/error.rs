/// What can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter was found.
    #[error("no GPU adapter found (is a driver installed? on Debian, Vulkan's: mesa-vulkan-drivers): {0}")]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("the adapter {adapter} refused a device: {reason}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// wgpu's message.
        reason: String,
    },
    /// A device whose limits are below [`Gpu::required_limits`](crate::Gpu::required_limits).
    #[error(
        "the device on {adapter} has {limit} = {available}, subdiv-gpu needs {required} \
         (request subdiv_gpu::Gpu::required_limits() or better)"
    )]
    Limit {
        /// The adapter's name.
        adapter: String,
        /// The limit's name, as in [`wgpu::Limits`].
        limit: &'static str,
        /// What subdiv-gpu needs.
        required: u64,
        /// What the device has.
        available: u64,
    },
    /// An index past the tessellation's vertices.
    #[error("index {index} names no vertex (there are {vertices})")]
    Indices {
        /// The index.
        index: u32,
        /// The number of vertices.
        vertices: usize,
    },
    /// Data larger than the device can hold in one buffer.
    #[error("the {what} take {bytes} bytes, more than the device's limit of {limit}")]
    TooLarge {
        /// What did not fit.
        what: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's limit.
        limit: u64,
    },
    /// Reading a buffer back failed (the device was lost).
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// The CPU tessellator refused the input, or a cage broke its rules
    /// ([`TessError::CageLength`](subdiv_tess::TessError::CageLength),
    /// [`TessError::CagePosition`](subdiv_tess::TessError::CagePosition)).
    #[error(transparent)]
    Tessellation(#[from] subdiv_tess::TessError),
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
}
