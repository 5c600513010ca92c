//! The wgpu renderer: the rust-gpu kernel dispatched one thread per pixel,
//! progressive accumulation in a GPU buffer, and the display pass.

use std::sync::{Arc, Mutex};

use pt_core::{AccumPixel, FrameParams, Sphere, WORKGROUP_SIZE, Wall};
use wgpu::util::DeviceExt;

/// The kernel's SPIR-V, built by `build.rs` with rust-gpu.
pub const KERNEL_SPV: &[u8] = include_bytes!(env!("PT_KERNEL_SPV"));

/// Errors of the GPU backend.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found, not even a software Vulkan driver; install a Vulkan driver \
         (on Debian: `apt-get install mesa-vulkan-drivers` for lavapipe) or use `--backend cpu`"
    )]
    NoAdapter,
    /// The adapter would not create a device.
    #[error("the adapter {adapter} could not create a device: {source}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's reason.
        source: wgpu::RequestDeviceError,
    },
    /// The device was lost (driver reset, GPU removed, out of memory).
    #[error("the GPU device was lost: {0}")]
    DeviceLost(String),
    /// wgpu rejected a resource or the kernel.
    #[error("GPU error: {0}")]
    Validation(String),
    /// The image does not fit the adapter's buffer limits.
    #[error(
        "a {width}x{height} image needs a {bytes}-byte GPU buffer, above this adapter's limit of {limit} bytes"
    )]
    TooLarge {
        /// Width asked for.
        width: u32,
        /// Height asked for.
        height: u32,
        /// Bytes needed.
        bytes: u64,
        /// The adapter's limit.
        limit: u64,
    },
}

/// A device and queue on the best adapter available, with its description.
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter: name, backend, driver, type.
    pub adapter_info: wgpu::AdapterInfo,
    /// Set by the device-lost callback or the uncaptured-error handler.
    failure: Arc<Mutex<Option<String>>>,
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
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Self::with_instance(&instance, None)
    }

    /// A context on the best adapter of `instance` that can present to
    /// `surface` when one is given.
    pub fn with_instance(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let adapter = adapters
            .into_iter()
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .min_by_key(|a| adapter_rank(a.get_info().device_type))
            .ok_or(GpuError::NoAdapter)?;
        let adapter_info = adapter.get_info();
        // Timestamp queries time the kernel where the adapter has them.
        let required_features = adapter.features()
            & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("pathtracer"),
            required_features,
            // The adapter's own limits: large images need large buffers.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|source| GpuError::RequestDevice {
            adapter: adapter_info.name.clone(),
            source,
        })?;

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
        Ok(Self {
            device,
            queue,
            adapter_info,
            failure,
        })
    }

    /// "name (backend, driver driver_info)", for reports.
    pub fn adapter_description(&self) -> String {
        let i = &self.adapter_info;
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        )
    }

    /// Whether this adapter is a software rasteriser (lavapipe).
    pub fn is_software(&self) -> bool {
        self.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// Waits for all submitted work, then reports a lost device or an
    /// uncaptured error that happened meanwhile.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        self.check()
    }

    /// Reports a lost device or uncaptured error seen so far.
    pub fn check(&self) -> Result<(), GpuError> {
        match self.failure.lock().ok().and_then(|f| f.clone()) {
            Some(msg) if msg.contains("Lost") || msg.contains("lost") => {
                Err(GpuError::DeviceLost(msg))
            }
            Some(msg) => Err(GpuError::Validation(msg)),
            None => Ok(()),
        }
    }

    /// Copies `size` bytes of `src` to the host.
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| GpuError::DeviceLost(e.to_string()))?
            .map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        let bytes = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::Validation(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

/// The kernel module. naga's SPIR-V front end reads what rust-gpu emits for
/// this kernel, so wgpu validates it like any shader: no passthrough, no
/// unchecked module.
fn kernel_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("pt-kernel"),
        source: wgpu::util::make_spirv(KERNEL_SPV),
    })
}

/// The progressive GPU renderer for one scene and image size.
pub struct GpuRenderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    trace_layout: wgpu::BindGroupLayout,
    display_layout: wgpu::BindGroupLayout,
    accumulate: wgpu::ComputePipeline,
    display: wgpu::ComputePipeline,
    params_buf: wgpu::Buffer,
    walls_buf: wgpu::Buffer,
    spheres_buf: wgpu::Buffer,
    accum_buf: wgpu::Buffer,
    display_buf: wgpu::Buffer,
    trace_group: wgpu::BindGroup,
    display_group: wgpu::BindGroup,
    params: FrameParams,
    /// Index of the next frame: distinct per dispatch, part of the RNG seed.
    next_frame: u32,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A layout of the uniform `FrameParams` at binding 0 plus `storage`.
fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    storage: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    let mut entries = vec![wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<FrameParams>() as u64),
        },
        count: None,
    }];
    entries.extend_from_slice(storage);
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("pt-kernel"),
        layout,
        entries: &entries,
    })
}

/// A storage buffer holding `data`, at least one element long (wgpu
/// rejects empty bindings; the kernel reads `count` elements only).
fn storage_buffer<T: bytemuck::Pod>(
    device: &wgpu::Device,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    let one = [T::zeroed()];
    let data = if data.is_empty() { &one[..] } else { data };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(data),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

impl GpuRenderer {
    /// A renderer for `params` (size, camera, light, settings) and geometry.
    pub fn new(
        ctx: &GpuContext,
        params: FrameParams,
        walls: &[Wall],
        spheres: &[Sphere],
    ) -> Result<Self, GpuError> {
        let device = ctx.device.clone();
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = kernel_module(&device);

        // wgpu matches storage access exactly, and the accumulation buffer is
        // read-write for `accumulate` but read-only for `display`: one
        // layout per entry point, each with the bindings it uses.
        let trace_layout = bind_group_layout(
            &device,
            "accumulate",
            &[
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, false),
            ],
        );
        let display_layout = bind_group_layout(
            &device,
            "display",
            &[storage_entry(3, true), storage_entry(4, false)],
        );
        let pipeline = |entry: &str, layout: &wgpu::BindGroupLayout| {
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let accumulate = pipeline("accumulate", &trace_layout);
        let display = pipeline("display", &display_layout);

        let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let walls_buf = storage_buffer(&device, "walls", walls);
        let spheres_buf = storage_buffer(&device, "spheres", spheres);
        let (accum_buf, display_buf) = Self::image_buffers(&device, params.width, params.height)?;
        let trace_group = bind_group(
            &device,
            &trace_layout,
            &[
                (0, &params_buf),
                (1, &walls_buf),
                (2, &spheres_buf),
                (3, &accum_buf),
            ],
        );
        let display_group = bind_group(
            &device,
            &display_layout,
            &[(0, &params_buf), (3, &accum_buf), (4, &display_buf)],
        );
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Validation(e.to_string()));
        }
        Ok(Self {
            device,
            queue: ctx.queue.clone(),
            trace_layout,
            display_layout,
            accumulate,
            display,
            params_buf,
            walls_buf,
            spheres_buf,
            accum_buf,
            display_buf,
            trace_group,
            display_group,
            params,
            next_frame: 0,
        })
    }

    fn image_buffers(
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let pixels = width as u64 * height as u64;
        let bytes = pixels * size_of::<AccumPixel>() as u64;
        let limits = device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge {
                width,
                height,
                bytes,
                limit,
            });
        }
        let accum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accumulation"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            // New buffers are zeroed by wgpu: an empty accumulation.
            mapped_at_creation: false,
        });
        let display = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("display"),
            size: pixels * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok((accum, display))
    }

    /// The current parameters.
    pub fn params(&self) -> &FrameParams {
        &self.params
    }

    /// Replaces the parameters. A change of image size reallocates the
    /// image buffers; the caller decides whether accumulation restarts.
    pub fn set_params(&mut self, params: FrameParams) -> Result<(), GpuError> {
        if (params.width, params.height) != (self.params.width, self.params.height) {
            let (accum, display) = Self::image_buffers(&self.device, params.width, params.height)?;
            self.accum_buf = accum;
            self.display_buf = display;
            self.rebind();
            self.next_frame = 0;
        }
        self.params = params;
        Ok(())
    }

    /// Replaces the geometry (walls and spheres).
    pub fn set_geometry(&mut self, walls: &[Wall], spheres: &[Sphere]) {
        self.walls_buf = storage_buffer(&self.device, "walls", walls);
        self.spheres_buf = storage_buffer(&self.device, "spheres", spheres);
        self.params.wall_count = walls.len() as u32;
        self.params.sphere_count = spheres.len() as u32;
        self.rebind();
    }

    fn rebind(&mut self) {
        self.trace_group = bind_group(
            &self.device,
            &self.trace_layout,
            &[
                (0, &self.params_buf),
                (1, &self.walls_buf),
                (2, &self.spheres_buf),
                (3, &self.accum_buf),
            ],
        );
        self.display_group = bind_group(
            &self.device,
            &self.display_layout,
            &[
                (0, &self.params_buf),
                (3, &self.accum_buf),
                (4, &self.display_buf),
            ],
        );
    }

    /// Clears the accumulated image and restarts the frame count.
    pub fn reset(&mut self) {
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.accum_buf, 0, None);
        self.queue.submit([encoder.finish()]);
        self.next_frame = 0;
    }

    /// Frames accumulated since the last reset.
    pub fn frames(&self) -> u32 {
        self.next_frame
    }

    fn workgroups(&self) -> (u32, u32) {
        (
            self.params.width.div_ceil(WORKGROUP_SIZE),
            self.params.height.div_ceil(WORKGROUP_SIZE),
        )
    }

    /// Submits one frame of `samples` samples per pixel. Nothing waits: the
    /// queue orders this parameter write before the frame's dispatch.
    pub fn submit_frame(&mut self, samples: u32) {
        self.params.frame = self.next_frame;
        self.params.samples_per_frame = samples;
        self.queue
            .write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.encode_accumulate(&mut encoder);
        self.queue.submit([encoder.finish()]);
        self.next_frame += 1;
    }

    /// Records the accumulation dispatch with the parameters last written.
    pub fn encode_accumulate(&self, encoder: &mut wgpu::CommandEncoder) {
        let (x, y) = self.workgroups();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("accumulate"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.accumulate);
        pass.set_bind_group(0, &self.trace_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Records the display pass (exposure, tone map, sRGB into the display
    /// buffer) with the parameters last written.
    pub fn encode_display(&self, encoder: &mut wgpu::CommandEncoder) {
        let (x, y) = self.workgroups();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("display"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.display);
        pass.set_bind_group(0, &self.display_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Runs the display pass with `exposure` (stops) and `tonemap`.
    pub fn submit_display(&mut self, exposure: f32, tonemap: u32) {
        self.params.exposure = exposure;
        self.params.tonemap = tonemap;
        self.queue
            .write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.encode_display(&mut encoder);
        self.queue.submit([encoder.finish()]);
    }

    /// The display buffer (RGBA8 per pixel, row 0 at the top): what the
    /// viewer copies to its texture.
    pub fn display_buffer(&self) -> &wgpu::Buffer {
        &self.display_buf
    }

    /// Reads the accumulation buffer back (waits for the GPU).
    pub fn read_accum(&self, ctx: &GpuContext) -> Result<Vec<AccumPixel>, GpuError> {
        let bytes = ctx.read_buffer(&self.accum_buf, self.accum_buf.size())?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Reads the display buffer back (waits for the GPU).
    pub fn read_display(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let bytes = ctx.read_buffer(&self.display_buf, self.display_buf.size())?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
