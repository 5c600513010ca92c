//! The progressive GPU renderer for one scene and image tile.

use std::sync::Arc;

use pt_core::small_scene::{SMALL_SCENE_SIZES, scene_constants, smallest_fit, smallest_fit_compiled};
use pt_core::{AccumPixel, FrameParams, Geometry, Sphere, Tile, WORKGROUP_SIZE, Wall};
use wgpu::util::DeviceExt;

use super::bindings::{ACCUM, DISPLAY, GEOMETRY, NON_FINITE, PARAMS, bind_group};
use super::context::PendingRead;
use super::kernel::{
    Kernel, SmallKernels, SmallVariant, TraceKernel, WORKGROUP_SHAPES, compute_pipeline, small_scene_index,
};
use super::{GpuContext, GpuError, GpuTimer};
use crate::scene::Scene;

/// The progressive GPU renderer for one scene and one tile of its image
/// (`FrameParams::tile`, the whole image unless a render is tiled).
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
    /// The small-scene kernels (`kernel::small_scene_entries`), where they
    /// are chosen.
    accumulate_small: Option<Arc<SmallKernels>>,
    /// `smallest_fit` of the current scene and light: worked out when they
    /// change, not every frame.
    small_fit: Option<usize>,
    /// `smallest_fit_compiled` of them: the capacity a specialized
    /// pipeline takes, which also holds walls that can block the light.
    compiled_fit: Option<usize>,
    /// Whether the small-scene pipeline is specialized to the scene
    /// (`TraceKernel::Specialized`).
    specialize: bool,
    /// That pipeline, for the current scene, settings and strategy
    /// (`SmallKernels::specialized` keeps it with its constants and makes
    /// another when they change).
    specialized: Option<wgpu::ComputePipeline>,
    /// Index of the next frame: distinct per dispatch, part of the RNG seed.
    next_frame: u32,
    /// Samples per pixel accumulated since the last reset (Sobol index).
    samples_done: u32,
    /// Workgroup size of the `accumulate` pipeline in use.
    trace_shape: (u32, u32),
}

/// The uniform buffer holding `geometry`.
fn geometry_buffer(device: &wgpu::Device, geometry: &Geometry) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("geometry"),
        contents: bytemuck::bytes_of(geometry),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

/// The most bytes one accumulation buffer may have on `device`: the
/// smaller of its largest storage binding and its largest buffer (128 MiB
/// on lavapipe and WebGPU's defaults). A tile's display buffer is an eighth
/// of that.
pub fn max_image_bytes(device: &wgpu::Device) -> u64 {
    let limits = device.limits();
    limits.max_storage_buffer_binding_size.min(limits.max_buffer_size)
}

impl GpuRenderer {
    /// A renderer for `params` (size, camera, light, settings) and geometry,
    /// on the adapter's [`GpuRenderer::default_trace_kernel`].
    pub fn new(ctx: &GpuContext, params: FrameParams, walls: &[Wall], spheres: &[Sphere]) -> Result<Self, GpuError> {
        Self::with_trace_kernel(ctx, params, walls, spheres, Self::default_trace_kernel(ctx))
    }

    /// [`GpuRenderer::new`] on trace kernel `kernel` (a viewer that edits
    /// the scene takes `TraceKernel::unspecialized` of the default).
    pub fn with_trace_kernel(
        ctx: &GpuContext,
        params: FrameParams,
        walls: &[Wall],
        spheres: &[Sphere],
        kernel: TraceKernel,
    ) -> Result<Self, GpuError> {
        let device = ctx.device.clone();
        // A browser resolves the scope's promise only after this call
        // returns, so there errors reach the uncaptured-error handler
        // (`GpuContext::check`) instead.
        #[cfg(not(target_arch = "wasm32"))]
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let Kernel { trace_layout, display_layout, accumulate, display, .. } = ctx.kernel().clone();

        let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        });
        let geometry = Box::new(crate::scene::geometry(walls, spheres)?);
        let geometry_buf = geometry_buffer(&device, &geometry);
        let (accum_buf, display_buf) = Self::image_buffers(&device, params.tile)?;
        let non_finite_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("non-finite count"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let trace_group = bind_group(
            &device,
            &trace_layout,
            &[(PARAMS, &params_buf), (GEOMETRY, &geometry_buf), (ACCUM, &accum_buf), (NON_FINITE, &non_finite_buf)],
        );
        let display_group = bind_group(
            &device,
            &display_layout,
            &[(PARAMS, &params_buf), (ACCUM, &accum_buf), (DISPLAY, &display_buf)],
        );
        #[cfg(not(target_arch = "wasm32"))]
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Validation(e.to_string()));
        }
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
            compiled_fit: smallest_fit_compiled(&params, &geometry),
            geometry,
            accumulate_small: None,
            specialize: false,
            specialized: None,
            next_frame: 0,
            samples_done: 0,
            trace_shape: (WORKGROUP_SIZE, WORKGROUP_SIZE),
        };
        renderer.set_trace_kernel(ctx, kernel);
        Ok(renderer)
    }

    /// The accumulation and display buffers of `tile`.
    fn image_buffers(device: &wgpu::Device, tile: Tile) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let pixels = tile.pixels();
        let bytes = pixels * size_of::<AccumPixel>() as u64;
        let limit = max_image_bytes(device);
        if bytes > limit {
            return Err(GpuError::TooLarge { width: tile.width, height: tile.height, bytes, limit });
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

    /// Replaces the parameters. A change of tile (the image size, for an
    /// untiled renderer) reallocates the image buffers; the caller decides
    /// whether accumulation restarts.
    pub fn set_params(&mut self, params: FrameParams) -> Result<(), GpuError> {
        if params.tile != self.params.tile {
            let (accum, display) = Self::image_buffers(&self.device, params.tile)?;
            self.accum_buf = accum;
            self.display_buf = display;
            self.rebind();
            self.next_frame = 0;
            self.samples_done = 0;
        }
        self.params = params;
        self.refit();
        Ok(())
    }

    /// Replaces the geometry (walls and spheres). The block has a fixed
    /// size, so it is rewritten in place (ordered before the next frame).
    pub fn set_geometry(&mut self, walls: &[Wall], spheres: &[Sphere]) -> Result<(), GpuError> {
        *self.geometry = crate::scene::geometry(walls, spheres)?;
        self.queue.write_buffer(&self.geometry_buf, 0, bytemuck::bytes_of(&*self.geometry));
        self.params.wall_count = walls.len() as u32;
        self.params.sphere_count = spheres.len() as u32;
        self.refit();
        Ok(())
    }

    /// The capacities that hold the current scene and light, and the
    /// specialized pipeline for them.
    fn refit(&mut self) {
        self.small_fit = smallest_fit(&self.params, &self.geometry);
        self.compiled_fit = smallest_fit_compiled(&self.params, &self.geometry);
        self.specialize_pipeline();
    }

    /// The specialized small-scene pipeline for the current scene, settings
    /// and strategy, where one is chosen and the scene fits it compiled in.
    fn specialize_pipeline(&mut self) {
        let (Some(size), Some(kernels), true) = (self.compiled_fit, &self.accumulate_small, self.specialize) else {
            self.specialized = None;
            return;
        };
        let constants = match SMALL_SCENE_SIZES[size] {
            (5, 2) => scene_constants::<5, 2>(&self.params, &self.geometry),
            (5, 8) => scene_constants::<5, 8>(&self.params, &self.geometry),
            (8, 16) => scene_constants::<8, 16>(&self.params, &self.geometry),
            _ => unreachable!("one arm per capacity of SMALL_SCENE_SIZES (a GPU test specializes each)"),
        };
        let index = small_scene_index(size, SmallVariant::of(&self.params));
        self.specialized = kernels.specialized(index, &constants);
    }

    fn rebind(&mut self) {
        self.trace_group = bind_group(
            &self.device,
            &self.trace_layout,
            &[
                (PARAMS, &self.params_buf),
                (GEOMETRY, &self.geometry_buf),
                (ACCUM, &self.accum_buf),
                (NON_FINITE, &self.non_finite_buf),
            ],
        );
        self.display_group = bind_group(
            &self.device,
            &self.display_layout,
            &[(PARAMS, &self.params_buf), (ACCUM, &self.accum_buf), (DISPLAY, &self.display_buf)],
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

    /// Continues a render that stopped after `frames` frames and `samples`
    /// samples per pixel: the next frame gets that frame index and Sobol
    /// offset, as it would have in one render (a part of a split render).
    pub fn start_at(&mut self, frames: u32, samples: u32) {
        self.next_frame = crate::renderer::frame_index(frames);
        self.samples_done = samples;
    }

    /// Frames accumulated since the last reset.
    pub fn frames(&self) -> u32 {
        self.next_frame
    }

    fn workgroups(&self) -> (u32, u32) {
        (self.params.tile.width.div_ceil(WORKGROUP_SIZE), self.params.tile.height.div_ceil(WORKGROUP_SIZE))
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
        self.specialized = None;
    }

    /// The trace kernel a renderer on `ctx` starts with: on software
    /// adapters (lavapipe, SwiftShader) and NVIDIA's, the small-scene
    /// kernel with the scene compiled in (for the scenes it holds), which
    /// drops the code of every feature the scene's flags leave off and
    /// folds the scene's values into the instructions: about 7% more
    /// samples per second than the same kernel reading the scene from
    /// buffers on lavapipe, 1.3x on an NVIDIA H200. The general kernel on
    /// the others (AMD, Intel, Apple GPUs), whose compilers may keep the
    /// unrolled scene in registers less well, until a run there says
    /// otherwise (`pathtracer bench throughput` times every form;
    /// docs/ARCHITECTURE.md has the figures). A renderer whose scene
    /// changes as a user edits it (the viewer) asks for
    /// [`TraceKernel::unspecialized`] of this, so that no edit waits for a
    /// pipeline.
    pub fn default_trace_kernel(ctx: &GpuContext) -> TraceKernel {
        const NVIDIA: u32 = 0x10de;
        if ctx.is_software() || ctx.adapter_info.vendor == NVIDIA {
            TraceKernel::Specialized
        } else {
            TraceKernel::General
        }
    }

    /// The notice for a user whose scene a renderer asking for `kernel`
    /// (the adapter's default, or its unspecialized form in the viewer)
    /// traces with the general kernel instead
    /// ([`super::kernel::small_scene_misfit`] says why); `None` where
    /// `kernel` is the general one or the scene fits.
    pub fn general_kernel_notice(scene: &Scene, kernel: TraceKernel) -> Option<String> {
        if kernel == TraceKernel::General {
            return None;
        }
        // The fit depends on the counts, the walls and the light only: no
        // flags (whose defaults take a pass over the scene) are worked out.
        let params = scene.frame_params_with_flags(&scene.render, 1, 0, 0);
        let compiled_in = kernel == TraceKernel::Specialized;
        let why = super::kernel::small_scene_misfit(&params, &scene.geometry().ok()?, compiled_in)?;
        Some(format!("note: the general kernel traces this scene, several times slower on this adapter: {why}"))
    }

    /// Chooses the form of the trace kernel (compiled now if need be; the
    /// renderer starts with [`GpuRenderer::default_trace_kernel`]). The small-scene kernel
    /// comes in the default 8x8 shape only.
    pub fn set_trace_kernel(&mut self, ctx: &GpuContext, kernel: TraceKernel) {
        if kernel == TraceKernel::General {
            self.accumulate_small = None;
        } else {
            self.set_workgroup_shape(ctx, 0);
            self.accumulate_small = Some(Arc::clone(ctx.small_kernels()));
        }
        self.specialize = kernel == TraceKernel::Specialized;
        self.specialize_pipeline();
    }

    /// The small-scene pipeline the next frame runs, if any: where the
    /// small-scene kernel is chosen, the smallest capacity that holds the
    /// scene, specialized to it where that is chosen and could be made
    /// (else reading the buffers, where the scene fits that form).
    fn small_pipeline(&self) -> Option<&wgpu::ComputePipeline> {
        if let Some(pipeline) = &self.specialized {
            return Some(pipeline);
        }
        let index = small_scene_index(self.small_fit?, SmallVariant::of(&self.params));
        self.accumulate_small.as_ref()?.get(index)
    }

    /// The kernel the next frame runs: the small-scene kernel where it is
    /// chosen and the scene fits it (specialized where that is chosen and
    /// was made), else the general one.
    pub fn trace_kernel(&self) -> TraceKernel {
        if self.specialized.is_some() {
            TraceKernel::Specialized
        } else if self.small_pipeline().is_some() {
            TraceKernel::SmallScene
        } else {
            TraceKernel::General
        }
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
        self.next_frame = crate::renderer::frame_index(self.next_frame.wrapping_add(1));
    }

    /// Writes the parameters (display settings included) without a frame.
    pub fn write_params(&self) {
        self.queue.write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
    }

    /// The (read-only storage) buffer of the parameters.
    pub fn params_buffer(&self) -> &wgpu::Buffer {
        &self.params_buf
    }

    /// Records the accumulation dispatch with the parameters last written.
    pub fn encode_accumulate(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let tile = self.params.tile;
        let (x, y) = (tile.width.div_ceil(self.trace_shape.0), tile.height.div_ceil(self.trace_shape.1));
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

    /// Starts copying the accumulation buffer to the host without waiting
    /// (for a browser, where nothing may block).
    pub fn start_read_accum(&self, ctx: &GpuContext) -> PendingRead {
        ctx.start_read(&self.accum_buf, self.accum_buf.size())
    }

    /// Starts copying the display buffer to the host without waiting.
    pub fn start_read_display(&self, ctx: &GpuContext) -> PendingRead {
        ctx.start_read(&self.display_buf, self.display_buf.size())
    }

    /// Starts copying the non-finite sample count to the host without waiting.
    pub fn start_read_non_finite(&self, ctx: &GpuContext) -> PendingRead {
        ctx.start_read(&self.non_finite_buf, 4)
    }
}
