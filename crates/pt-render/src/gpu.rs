//! The wgpu renderer: the rust-gpu kernel dispatched one thread per pixel,
//! progressive accumulation in a GPU buffer, and the display pass.

use std::sync::{Arc, Mutex};

use pt_core::small_scene::{SMALL_SCENE_SIZES, smallest_fit};
use pt_core::{AccumPixel, FrameParams, Geometry, Sphere, WORKGROUP_SIZE, Wall};
use wgpu::util::DeviceExt;

use crate::scene::TooManyObjects;

/// The kernel's SPIR-V: the committed module `shaders-rs/compiled/pt_kernel.spv`
/// unless `build.rs` was told to use another (`PT_KERNEL_SPV`, or the
/// `build-kernel` feature).
pub const KERNEL_SPV: &[u8] = include_bytes!(env!("PT_KERNEL_MODULE"));

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
    #[error("a {width}x{height} image needs a {bytes}-byte GPU buffer, above this adapter's limit of {limit} bytes")]
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
    /// More walls or spheres than the kernel's geometry block holds.
    #[error(transparent)]
    TooManyObjects(#[from] TooManyObjects),
}

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
    kernel: std::sync::OnceLock<Kernel>,
    /// The small-scene kernels, one per entry of `SMALL_SCENE_SIZES`,
    /// compiled on first use.
    small_kernels: std::sync::OnceLock<Vec<wgpu::ComputePipeline>>,
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
        // Timestamp queries time the kernel where the adapter has them.
        let required_features =
            adapter.features() & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("pathtracer"),
            required_features,
            // The adapter's own limits: large images need large buffers.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|source| GpuError::RequestDevice { adapter: adapter_info.name.clone(), source })?;

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
            adapter,
            failure,
            kernel: Default::default(),
            small_kernels: Default::default(),
        })
    }

    fn kernel(&self) -> &Kernel {
        self.kernel.get_or_init(|| Kernel::new(&self.device))
    }

    fn small_kernels(&self) -> &[wgpu::ComputePipeline] {
        self.small_kernels.get_or_init(|| {
            let k = self.kernel();
            let entry = |(w, s): (u32, u32)| format!("accumulate_small_{w}w_{s}s");
            SMALL_SCENE_SIZES
                .iter()
                .map(|&size| compute_pipeline(&self.device, &k.module, &k.trace_pipeline_layout, &entry(size)))
                .collect()
        })
    }

    /// The adapter (surface capabilities are asked of it).
    pub fn adapter(&self) -> &wgpu::Adapter {
        &self.adapter
    }

    /// "name (backend, driver driver_info)", for reports.
    pub fn adapter_description(&self) -> String {
        let i = &self.adapter_info;
        format!("{} ({:?}, {:?}, driver {} {})", i.name, i.backend, i.device_type, i.driver, i.driver_info)
    }

    /// Whether this adapter is a software rasteriser (lavapipe).
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
        rx.recv().map_err(|e| GpuError::DeviceLost(e.to_string()))?.map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        let bytes = staging.get_mapped_range(..).map_err(|e| GpuError::Validation(e.to_string()))?.to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

/// The compiled compute pipelines and their layouts, made once per device:
/// compiling them is the slow part of a renderer's creation (hundreds of
/// milliseconds on lavapipe), and renderers come and go (seeds, resizes).
#[derive(Clone)]
struct Kernel {
    trace_layout: wgpu::BindGroupLayout,
    display_layout: wgpu::BindGroupLayout,
    accumulate: wgpu::ComputePipeline,
    display: wgpu::ComputePipeline,
    /// For the other workgroup shapes (benchmarks): compiled on demand.
    module: wgpu::ShaderModule,
    trace_pipeline_layout: wgpu::PipelineLayout,
}

/// The two forms of the trace kernel.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TraceKernel {
    /// `accumulate` (and its other workgroup shapes): the uniform block read
    /// in loops, for any scene. The default on GPUs.
    General,
    /// `accumulate_small_*`: a copy of a small scene read at constant
    /// indices (`pt_core::small_scene`), in the smallest capacity that holds
    /// the scene; frames of scenes that fit none use `General`. The default
    /// on CPU adapters (lavapipe), where it measured faster
    /// (docs/ARCHITECTURE.md).
    SmallScene,
}

impl TraceKernel {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::General => "general kernel",
            Self::SmallScene => "small-scene kernel",
        }
    }
}

/// The workgroup shapes the kernel has an `accumulate` entry point for:
/// (entry point, width, height). The first is the default.
pub const WORKGROUP_SHAPES: [(&str, u32, u32); 4] = [
    ("accumulate", 8, 8),
    ("accumulate_16x4_groups", 16, 4),
    ("accumulate_32x2_groups", 32, 2),
    ("accumulate_4x4_groups", 4, 4),
];

fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

impl Kernel {
    fn new(device: &wgpu::Device) -> Self {
        let module = kernel_module(device);
        // wgpu matches storage access exactly, and the accumulation buffer is
        // read-write for `accumulate` but read-only for `display`: one
        // layout per entry point, each with the bindings it uses.
        let trace_layout = bind_group_layout(
            device,
            "accumulate",
            &[uniform_entry::<Geometry>(1), storage_entry(2, false), storage_entry(4, false)],
        );
        let display_layout = bind_group_layout(device, "display", &[storage_entry(2, true), storage_entry(3, false)]);
        let pipeline_layout = |label: &str, layout: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            })
        };
        let trace_pipeline_layout = pipeline_layout("accumulate", &trace_layout);
        let accumulate = compute_pipeline(device, &module, &trace_pipeline_layout, "accumulate");
        let display = compute_pipeline(device, &module, &pipeline_layout("display", &display_layout), "display");
        Self { trace_layout, display_layout, accumulate, display, module, trace_pipeline_layout }
    }
}

/// The kernel module. naga's SPIR-V front end reads what rust-gpu emits for
/// this kernel, so wgpu validates it like any shader (no passthrough), but
/// without the runtime checks naga would add to the code it writes out: a
/// clamp on every array index, and a counter on every loop that breaks out
/// after 2^64 iterations. The kernel is Rust: rust-gpu keeps Rust's own
/// bounds checks, and every loop in it is bounded (the per-pixel loop by
/// `samples_per_frame` paths of at most `max_bounces + 1` segments, the
/// object loops by counts clamped to the arrays, the shadow-wall loop by a
/// 32-bit mask shifted each turn). What it saved: docs/ARCHITECTURE.md.
fn kernel_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor { label: Some("pt-kernel"), source: wgpu::util::make_spirv(KERNEL_SPV) };
    // SAFETY: see above: the kernel indexes only through Rust's bounds
    // checks and has no unbounded loop, which is what the unchecked
    // options ask of the caller.
    unsafe { device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked()) }
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
    geometry_buf: wgpu::Buffer,
    accum_buf: wgpu::Buffer,
    display_buf: wgpu::Buffer,
    /// One u32: non-finite samples discarded since the last reset.
    non_finite_buf: wgpu::Buffer,
    trace_group: wgpu::BindGroup,
    display_group: wgpu::BindGroup,
    params: FrameParams,
    /// The geometry block's contents, for `small_scene::smallest_fit`.
    geometry: Box<Geometry>,
    /// The small-scene kernels (one per entry of `SMALL_SCENE_SIZES`),
    /// where they are chosen.
    accumulate_small: Option<Vec<wgpu::ComputePipeline>>,
    /// `smallest_fit` of the current scene and light: worked out when they
    /// change, not every frame.
    small_fit: Option<usize>,
    /// Index of the next frame: distinct per dispatch, part of the RNG seed.
    next_frame: u32,
    /// Samples per pixel accumulated since the last reset (Sobol index).
    samples_done: u32,
    /// Workgroup size of the `accumulate` pipeline in use.
    trace_shape: (u32, u32),
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

/// A uniform block of type `T` at `binding`, for the compute stage.
fn uniform_entry<T>(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<T>() as u64),
        },
        count: None,
    }
}

/// A layout of the uniform `FrameParams` at binding 0 plus `others`.
fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    others: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    let mut entries = vec![uniform_entry::<FrameParams>(0)];
    entries.extend_from_slice(others);
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> =
        buffers.iter().map(|&(binding, b)| wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }).collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some("pt-kernel"), layout, entries: &entries })
}

/// The uniform buffer holding `geometry`.
fn geometry_buffer(device: &wgpu::Device, geometry: &Geometry) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("geometry"),
        contents: bytemuck::bytes_of(geometry),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

impl GpuRenderer {
    /// A renderer for `params` (size, camera, light, settings) and geometry.
    pub fn new(ctx: &GpuContext, params: FrameParams, walls: &[Wall], spheres: &[Sphere]) -> Result<Self, GpuError> {
        let device = ctx.device.clone();
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let Kernel { trace_layout, display_layout, accumulate, display, .. } = ctx.kernel().clone();

        let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let geometry = Box::new(crate::scene::geometry(walls, spheres)?);
        let geometry_buf = geometry_buffer(&device, &geometry);
        let (accum_buf, display_buf) = Self::image_buffers(&device, params.width, params.height)?;
        let non_finite_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("non-finite count"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let trace_group = bind_group(
            &device,
            &trace_layout,
            &[(0, &params_buf), (1, &geometry_buf), (2, &accum_buf), (4, &non_finite_buf)],
        );
        let display_group =
            bind_group(&device, &display_layout, &[(0, &params_buf), (2, &accum_buf), (3, &display_buf)]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Validation(e.to_string()));
        }
        let kernel = Self::default_trace_kernel(ctx);
        let mut renderer = Self {
            device,
            queue: ctx.queue.clone(),
            trace_layout,
            display_layout,
            accumulate,
            display,
            params_buf,
            geometry_buf,
            accum_buf,
            display_buf,
            non_finite_buf,
            trace_group,
            display_group,
            params,
            small_fit: smallest_fit(&params, &geometry),
            geometry,
            accumulate_small: None,
            next_frame: 0,
            samples_done: 0,
            trace_shape: (WORKGROUP_SIZE, WORKGROUP_SIZE),
        };
        renderer.set_trace_kernel(ctx, kernel);
        Ok(renderer)
    }

    fn image_buffers(device: &wgpu::Device, width: u32, height: u32) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let pixels = width as u64 * height as u64;
        let bytes = pixels * size_of::<AccumPixel>() as u64;
        let limits = device.limits();
        let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
        if bytes > limit {
            return Err(GpuError::TooLarge { width, height, bytes, limit });
        }
        let accum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accumulation"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
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
            self.samples_done = 0;
        }
        self.params = params;
        self.small_fit = smallest_fit(&self.params, &self.geometry);
        Ok(())
    }

    /// Replaces the geometry (walls and spheres). The block has a fixed
    /// size, so it is rewritten in place (ordered before the next frame).
    pub fn set_geometry(&mut self, walls: &[Wall], spheres: &[Sphere]) -> Result<(), GpuError> {
        *self.geometry = crate::scene::geometry(walls, spheres)?;
        self.queue.write_buffer(&self.geometry_buf, 0, bytemuck::bytes_of(&*self.geometry));
        self.params.wall_count = walls.len() as u32;
        self.params.sphere_count = spheres.len() as u32;
        self.small_fit = smallest_fit(&self.params, &self.geometry);
        Ok(())
    }

    fn rebind(&mut self) {
        self.trace_group = bind_group(
            &self.device,
            &self.trace_layout,
            &[(0, &self.params_buf), (1, &self.geometry_buf), (2, &self.accum_buf), (4, &self.non_finite_buf)],
        );
        self.display_group = bind_group(
            &self.device,
            &self.display_layout,
            &[(0, &self.params_buf), (2, &self.accum_buf), (3, &self.display_buf)],
        );
    }

    /// Clears the accumulated image and restarts the frame count.
    pub fn reset(&mut self) {
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.accum_buf, 0, None);
        encoder.clear_buffer(&self.non_finite_buf, 0, None);
        self.queue.submit([encoder.finish()]);
        self.next_frame = 0;
        self.samples_done = 0;
    }

    /// Frames accumulated since the last reset.
    pub fn frames(&self) -> u32 {
        self.next_frame
    }

    fn workgroups(&self) -> (u32, u32) {
        (self.params.width.div_ceil(WORKGROUP_SIZE), self.params.height.div_ceil(WORKGROUP_SIZE))
    }

    /// Traces with the general kernel's entry point of
    /// `WORKGROUP_SHAPES[shape]` (compiled now unless it is the default;
    /// benchmarks compare the shapes).
    pub fn set_workgroup_shape(&mut self, ctx: &GpuContext, shape: usize) {
        let (entry, w, h) = WORKGROUP_SHAPES[shape];
        let k = ctx.kernel();
        // The default shape is compiled already.
        self.accumulate = if shape == 0 {
            k.accumulate.clone()
        } else {
            compute_pipeline(&ctx.device, &k.module, &k.trace_pipeline_layout, entry)
        };
        self.trace_shape = (w, h);
        self.accumulate_small = None;
    }

    /// The trace kernel a renderer on `ctx` starts with: the small-scene
    /// kernel on CPU adapters, the general one on GPUs.
    pub fn default_trace_kernel(ctx: &GpuContext) -> TraceKernel {
        if ctx.is_software() { TraceKernel::SmallScene } else { TraceKernel::General }
    }

    /// Chooses the form of the trace kernel (compiled now if need be; the
    /// renderer starts with the adapter's default). The small-scene kernel
    /// comes in the default 8x8 shape only.
    pub fn set_trace_kernel(&mut self, ctx: &GpuContext, kernel: TraceKernel) {
        if kernel == TraceKernel::SmallScene {
            self.set_workgroup_shape(ctx, 0);
            self.accumulate_small = Some(ctx.small_kernels().to_vec());
        } else {
            self.accumulate_small = None;
        }
    }

    /// The small-scene pipeline the next frame runs, if any: where the
    /// small-scene kernel is chosen, the smallest capacity that holds the
    /// scene.
    fn small_pipeline(&self) -> Option<&wgpu::ComputePipeline> {
        self.accumulate_small.as_ref()?.get(self.small_fit?)
    }

    /// The kernel the next frame runs: the small-scene kernel where it is
    /// chosen and the scene fits it, else the general one.
    pub fn trace_kernel(&self) -> TraceKernel {
        if self.small_pipeline().is_some() { TraceKernel::SmallScene } else { TraceKernel::General }
    }

    /// Submits one frame of `samples` samples per pixel. Nothing waits: the
    /// queue orders this parameter write before the frame's dispatch.
    pub fn submit_frame(&mut self, samples: u32) {
        self.submit_frame_timed(samples, None);
    }

    /// [`GpuRenderer::submit_frame`], with the dispatch timed by `timer`
    /// when one is given (read it with [`GpuTimer::read_ms`]).
    pub fn submit_frame_timed(&mut self, samples: u32, timer: Option<&GpuTimer>) {
        self.params.frame = self.next_frame;
        self.params.samples_per_frame = samples;
        self.params.sample_offset = self.samples_done;
        self.samples_done = self.samples_done.saturating_add(samples);
        self.write_params();
        let mut encoder = self.device.create_command_encoder(&Default::default());
        self.encode_accumulate(&mut encoder, timer.map(GpuTimer::pass_writes));
        if let Some(t) = timer {
            t.resolve(&mut encoder);
        }
        self.queue.submit([encoder.finish()]);
        self.next_frame += 1;
    }

    /// Writes the parameters (display settings included) without a frame.
    pub fn write_params(&self) {
        self.queue.write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
    }

    /// The uniform buffer of the parameters.
    pub fn params_buffer(&self) -> &wgpu::Buffer {
        &self.params_buf
    }

    /// Records the accumulation dispatch with the parameters last written.
    pub fn encode_accumulate(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let (x, y) = (self.params.width.div_ceil(self.trace_shape.0), self.params.height.div_ceil(self.trace_shape.1));
        let mut pass =
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("accumulate"), timestamp_writes });
        let pipeline = self.small_pipeline().unwrap_or(&self.accumulate);
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.trace_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Records the display pass (exposure, tone map, sRGB into the display
    /// buffer) with the parameters last written.
    pub fn encode_display(&self, encoder: &mut wgpu::CommandEncoder) {
        let (x, y) = self.workgroups();
        let mut pass =
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("display"), timestamp_writes: None });
        pass.set_pipeline(&self.display);
        pass.set_bind_group(0, &self.display_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// Runs the display pass with `exposure` (stops) and `tonemap`.
    pub fn submit_display(&mut self, exposure: f32, tonemap: u32) {
        self.params.exposure = exposure;
        self.params.tonemap = tonemap;
        self.queue.write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
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

    /// Non-finite samples discarded since the last reset (waits for the GPU;
    /// four bytes cross the bus).
    pub fn read_non_finite(&self, ctx: &GpuContext) -> Result<u32, GpuError> {
        let bytes = ctx.read_buffer(&self.non_finite_buf, 4)?;
        Ok(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    }

    /// Reads the display buffer back (waits for the GPU).
    pub fn read_display(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let bytes = ctx.read_buffer(&self.display_buf, self.display_buf.size())?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// Times one compute pass with GPU timestamp queries, where the adapter has
/// them.
pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve_buf: wgpu::Buffer,
    read_buf: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

impl GpuTimer {
    /// A timer, or `None` when the adapter has no timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("frame timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let resolve_buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size: 16,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let read_buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps readback"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(Self { queries, resolve_buf, read_buf, period_ns: ctx.queue.get_timestamp_period() as f64 })
    }

    /// Timestamp writes at the beginning and end of a compute pass.
    pub fn pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(1),
        }
    }

    /// Records the copy of the two timestamps to the readable buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2, &self.resolve_buf, 0);
        encoder.copy_buffer_to_buffer(&self.resolve_buf, 0, &self.read_buf, 0, 16);
    }

    /// Milliseconds between the two timestamps of the last timed pass
    /// (waits for the GPU).
    pub fn read_ms(&self, ctx: &GpuContext) -> Result<f64, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        self.read_buf.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        ctx.wait()?;
        rx.recv().map_err(|e| GpuError::DeviceLost(e.to_string()))?.map_err(|e| GpuError::DeviceLost(e.to_string()))?;
        let t: [u64; 2] = {
            let view = self.read_buf.get_mapped_range(..).map_err(|e| GpuError::Validation(e.to_string()))?;
            bytemuck::pod_read_unaligned(&view[..16])
        };
        self.read_buf.unmap();
        Ok(t[1].saturating_sub(t[0]) as f64 * self.period_ns * 1e-6)
    }
}

/// Draws the display buffer onto a render target: the viewer's image.
pub struct Blit {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl Blit {
    /// A blit for render targets of `format`. A non-sRGB format shows the
    /// display buffer's sRGB bytes as they are.
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let device = &ctx.device;
        let module = kernel_module(device);
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty,
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("blit"),
            entries: &[
                entry(
                    0,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(size_of::<FrameParams>() as u64),
                    },
                ),
                entry(
                    3,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: true },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                ),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("blit"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("blit"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("blit_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("blit_fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        });
        Self { pipeline, layout }
    }

    /// The bind group for `renderer`'s current buffers (recreate it after a
    /// resize).
    pub fn bind_group(&self, ctx: &GpuContext, renderer: &GpuRenderer) -> wgpu::BindGroup {
        bind_group(&ctx.device, &self.layout, &[(0, renderer.params_buffer()), (3, renderer.display_buffer())])
    }

    /// Records the blit into a render pass.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
    }
}
