//! The device and queue on the best adapter, with the kernel compiled once
//! for every renderer made on it.

use std::sync::{Arc, Mutex, OnceLock};

use super::GpuError;
use super::kernel::{Kernel, SmallKernels};

/// A device and queue on the best adapter available, with its description.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter: name, backend, driver, type.
    pub adapter_info: wgpu::AdapterInfo,
    adapter: wgpu::Adapter,
    /// Set by the device-lost callback or the uncaptured-error handler.
    failure: Arc<Mutex<Option<String>>>,
    /// The kernel's pipelines, compiled on first use.
    kernel: OnceLock<Kernel>,
    /// The small-scene kernels (`kernel::small_scene_entries`), each
    /// compiled on first use.
    small_kernels: OnceLock<Arc<SmallKernels>>,
}

/// Preference among adapter types: a real GPU first, the software driver
/// last but accepted.
fn adapter_rank(t: wgpu::DeviceType) -> u32 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

impl GpuContext {
    /// A headless context on the best adapter (discrete, integrated,
    /// virtual, then software such as lavapipe).
    pub fn new() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Self::with_instance(&instance, None)
    }

    /// A context on the best adapter of `instance` that can present to
    /// `surface` when one is given.
    pub fn with_instance(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<Self, GpuError> {
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let adapter = adapters
            .into_iter()
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .min_by_key(|a| adapter_rank(a.get_info().device_type))
            .ok_or(GpuError::NoAdapter)?;
        let adapter_info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&Self::device_descriptor(&adapter)))
            .map_err(|source| GpuError::RequestDevice { adapter: adapter_info.name, source })?;
        Ok(Self::from_device(adapter, device, queue))
    }

    /// What the renderer asks of a device on `adapter`: the adapter's own
    /// limits (large images need large buffers), and timestamp queries
    /// where the adapter has them. For callers that create the device
    /// themselves, such as the browser viewer's window framework.
    pub fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
        wgpu::DeviceDescriptor {
            label: Some("pathtracer"),
            required_features: adapter.features()
                & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS),
            required_limits: adapter.limits(),
            ..Default::default()
        }
    }

    /// A context on a device created elsewhere (with
    /// [`GpuContext::device_descriptor`]), for example by a window framework
    /// that must own the device, as in a browser.
    pub fn from_device(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let failure = Arc::new(Mutex::new(None));
        let lost = failure.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut f) = lost.lock() {
                f.get_or_insert(format!("{reason:?}: {message}"));
            }
        });
        let errors = failure.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut f) = errors.lock() {
                f.get_or_insert(e.to_string());
            }
        }));
        Self {
            device,
            queue,
            adapter_info: adapter.get_info(),
            adapter,
            failure,
            kernel: Default::default(),
            small_kernels: Default::default(),
        }
    }

    pub(super) fn kernel(&self) -> &Kernel {
        self.kernel.get_or_init(|| Kernel::new(&self.device))
    }

    pub(super) fn small_kernels(&self) -> &Arc<SmallKernels> {
        self.small_kernels.get_or_init(|| Arc::new(SmallKernels::new(&self.device, self.kernel())))
    }

    /// The adapter (surface capabilities are asked of it).
    pub fn adapter(&self) -> &wgpu::Adapter {
        &self.adapter
    }

    /// "name (backend, driver driver_info)", for reports. A browser names
    /// neither the adapter nor its driver.
    pub fn adapter_description(&self) -> String {
        let i = &self.adapter_info;
        match i.backend {
            wgpu::Backend::BrowserWebGpu => format!("the browser's WebGPU ({:?})", i.device_type),
            _ => format!("{} ({:?}, {:?}, driver {} {})", i.name, i.backend, i.device_type, i.driver, i.driver_info),
        }
    }

    /// Whether this adapter is a software rasteriser (lavapipe; SwiftShader
    /// in a browser).
    pub fn is_software(&self) -> bool {
        self.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// Waits for all submitted work, then reports a lost device or an
    /// uncaptured error that happened meanwhile.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        self.check()
    }

    /// Reports a lost device or uncaptured error seen so far.
    pub fn check(&self) -> Result<(), GpuError> {
        match self.failure.lock().ok().and_then(|f| f.clone()) {
            Some(msg) if msg.contains("Lost") || msg.contains("lost") => Err(GpuError::DeviceLost(msg)),
            Some(msg) => Err(GpuError::Validation(msg)),
            None => Ok(()),
        }
    }

    /// Copies `size` bytes of `src` to the host (waits for the GPU).
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let pending = self.start_read(src, size);
        self.wait()?;
        pending.try_take().unwrap_or_else(|| Err(GpuError::DeviceLost("a buffer copy never finished".into())))
    }

    /// Starts copying `size` bytes of `src` to the host; nothing waits.
    /// [`PendingRead::try_take`] gives the bytes once the GPU is done, which
    /// in a browser is after control went back to the page's event loop.
    pub fn start_read(&self, src: &wgpu::Buffer, size: u64) -> PendingRead {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let mapped = Arc::new(Mutex::new(None));
        let done = mapped.clone();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            if let Ok(mut d) = done.lock() {
                *d = Some(r);
            }
        });
        PendingRead { staging, mapped }
    }
}

/// A copy of a GPU buffer on its way to the host ([`GpuContext::start_read`]).
pub struct PendingRead {
    staging: wgpu::Buffer,
    mapped: Arc<Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>,
}

impl PendingRead {
    /// The bytes, once the copy has finished; `None` before. Never waits.
    pub fn try_take(&self) -> Option<Result<Vec<u8>, GpuError>> {
        let result = self.mapped.lock().ok()?.take()?;
        Some(result.map_err(|e| GpuError::DeviceLost(e.to_string())).and_then(|()| {
            let bytes = self.staging.get_mapped_range(..).map_err(|e| GpuError::Validation(e.to_string()))?.to_vec();
            self.staging.unmap();
            Ok(bytes)
        }))
    }
}
