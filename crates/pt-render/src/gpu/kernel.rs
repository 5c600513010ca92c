//! The kernel module and its compute pipelines.

use std::sync::{Mutex, OnceLock};

use pt_core::FrameParams;
use pt_core::Geometry;
use pt_core::bsdf::glow_probability;
use pt_core::integrator::{SamplerKind, connects, roulette_acts};
use pt_core::query::ShadowWalls;
use pt_core::small_scene::{SMALL_SCENE_SIZES, smallest_fit, smallest_fit_compiled};

use super::KERNEL_SPV;
use super::bindings::{ACCUM, DISPLAY, GEOMETRY, NON_FINITE, bind_group_layout, storage_entry, uniform_entry};

/// The compiled compute pipelines and their layouts, made once per device:
/// compiling them is the slow part of a renderer's creation (hundreds of
/// milliseconds on lavapipe), and renderers come and go (seeds, resizes).
#[derive(Clone)]
pub(super) struct Kernel {
    pub(super) trace_layout: wgpu::BindGroupLayout,
    pub(super) display_layout: wgpu::BindGroupLayout,
    pub(super) accumulate: wgpu::ComputePipeline,
    pub(super) display: wgpu::ComputePipeline,
    /// For the other workgroup shapes (benchmarks): compiled on demand.
    pub(super) module: wgpu::ShaderModule,
    pub(super) trace_pipeline_layout: wgpu::PipelineLayout,
}

/// The two forms of the trace kernel.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TraceKernel {
    /// `accumulate` (and its other workgroup shapes): the uniform block read
    /// in loops, for any scene. The default on GPUs.
    General,
    /// `accumulate_small_*`: a copy of a small scene read at constant
    /// indices (`pt_core::small_scene`), in the smallest capacity that holds
    /// the scene, with the sampler the flags pick compiled in; frames of
    /// scenes that fit none use `General`. What a renderer whose scene
    /// changes as it is edited (the viewer) runs where `Specialized` is
    /// the default (`TraceKernel::unspecialized`).
    SmallScene,
    /// The small-scene kernel with the scene's values (camera, light,
    /// settings, walls and spheres: `small_scene::scene_constants`)
    /// compiled into the pipeline as specialization constants, so that
    /// the driver folds them into the code: a pipeline per scene and
    /// strategy, made when the renderer first needs it (half a second and
    /// more on lavapipe). The default for renders of a fixed scene on
    /// software adapters and NVIDIA GPUs
    /// (`GpuRenderer::default_trace_kernel`). Scenes that fit no capacity
    /// use `General`.
    Specialized,
}

impl TraceKernel {
    /// Every form.
    pub const ALL: [TraceKernel; 3] = [TraceKernel::General, TraceKernel::SmallScene, TraceKernel::Specialized];

    /// The form that makes no pipeline per scene: `SmallScene` for
    /// `Specialized`, else itself. For a renderer whose scene changes
    /// as the user edits it.
    pub fn unspecialized(self) -> Self {
        if self == Self::Specialized { Self::SmallScene } else { self }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::General => "general kernel",
            Self::SmallScene => "small-scene kernel",
            Self::Specialized => "small-scene kernel, scene compiled in",
        }
    }
}

/// The optional code a small-scene entry point compiles in, in the
/// kernel's order. Connections come with the glow lobe (a light in a
/// corner takes both).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) enum SmallCode {
    /// The connections' code and the glow lobe's.
    Connected,
    /// The glow lobe's alone (`_unconnected`).
    Unconnected,
    /// Neither (`_unconnected_noglow`).
    Bare,
}

impl SmallCode {
    const ALL: [SmallCode; 3] = [SmallCode::Connected, SmallCode::Unconnected, SmallCode::Bare];

    /// The entry point name's suffix.
    fn suffix(self) -> &'static str {
        match self {
            SmallCode::Connected => "",
            SmallCode::Unconnected => "_unconnected",
            SmallCode::Bare => "_unconnected_noglow",
        }
    }
}

/// What a small-scene entry point compiles in beside its capacity: the
/// sampler, the optional code, and Russian roulette's code or not.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) struct SmallVariant {
    pub(super) sampler: SamplerKind,
    pub(super) code: SmallCode,
    /// Whether the roulette's code is in (else the name ends in
    /// `_noroulette`).
    pub(super) roulette: bool,
}

impl SmallVariant {
    /// Every variant, in the kernel's order: samplers in
    /// `SamplerKind::ALL`'s order, each with every [`SmallCode`], each with
    /// the roulette's code and without it.
    fn all() -> impl Iterator<Item = SmallVariant> {
        SamplerKind::ALL.into_iter().flat_map(|sampler| {
            SmallCode::ALL
                .into_iter()
                .flat_map(move |code| [true, false].map(move |roulette| SmallVariant { sampler, code, roulette }))
        })
    }

    /// The variant a frame of `params` needs: the sampler its flags pick,
    /// the connections' code only where they make connections, the glow
    /// lobe's only where they have it or the connections, and the
    /// roulette's only where it can act on a path
    /// (`pt_core::integrator::roulette_acts`). Leaving code out where the
    /// frame uses none of it renders the same samples, faster on lavapipe,
    /// which would run it masked.
    pub(super) fn of(params: &FrameParams) -> Self {
        let flags = params.flags;
        let code = if connects(flags) {
            SmallCode::Connected
        } else if glow_probability(flags) > 0.0 {
            SmallCode::Unconnected
        } else {
            SmallCode::Bare
        };
        Self { sampler: SamplerKind::of(flags), code, roulette: roulette_acts(params) }
    }
}

/// The entry point of the small-scene kernel of capacity (walls, spheres)
/// and `variant`.
pub(super) fn small_scene_entry((walls, spheres): (u32, u32), variant: SmallVariant) -> String {
    let sampler = match variant.sampler {
        SamplerKind::Independent => "pcg",
        SamplerKind::Sobol => "sobol",
        SamplerKind::SobolDeep => "sobol_deep",
    };
    let roulette = if variant.roulette { "" } else { "_noroulette" };
    format!("accumulate_small_{walls}w_{spheres}s_{sampler}{}{roulette}", variant.code.suffix())
}

/// Index of the small-scene pipeline of capacity `size` (an index in
/// `SMALL_SCENE_SIZES`) and `variant` in [`small_scene_entries`]' order.
pub(super) fn small_scene_index(size: usize, variant: SmallVariant) -> usize {
    let per_size = SamplerKind::ALL.len() * SmallCode::ALL.len() * 2;
    size * per_size
        + (variant.sampler as usize * SmallCode::ALL.len() + variant.code as usize) * 2
        + !variant.roulette as usize
}

/// Why no small-scene capacity holds a scene, read from the buffers or
/// `compiled_in` (specialized), in words for a notice: the renderer then
/// traces it with the general kernel, which makes the same image but which
/// lavapipe runs several times slower. `None` where a capacity of
/// `SMALL_SCENE_SIZES` holds it.
pub fn small_scene_misfit(params: &FrameParams, geometry: &Geometry, compiled_in: bool) -> Option<String> {
    let fit = if compiled_in { smallest_fit_compiled(params, geometry) } else { smallest_fit(params, geometry) };
    if fit.is_some() {
        return None;
    }
    let (walls, spheres) = SMALL_SCENE_SIZES.iter().fold((0, 0), |(w, s), &(a, b)| (w.max(a), s.max(b)));
    let mut why = Vec::new();
    if params.sphere_count > spheres {
        why.push(format!("{} spheres (the small-scene kernel holds {spheres})", params.sphere_count));
    }
    if params.wall_count > walls {
        why.push(format!("{} walls (the small-scene kernel holds {walls})", params.wall_count));
    }
    if !compiled_in && !ShadowWalls::new(params, geometry).is_empty() {
        why.push(
            "a wall that can block the light (the small-scene kernel holds one only with the scene compiled in, \
             which the viewer does not do)"
                .into(),
        );
    }
    Some(why.join(" and "))
}

/// Every small-scene entry point: capacities in `SMALL_SCENE_SIZES`' order,
/// each with every variant in `SmallVariant::all`'s order.
pub fn small_scene_entries() -> Vec<String> {
    SMALL_SCENE_SIZES.iter().flat_map(|&size| SmallVariant::all().map(move |v| small_scene_entry(size, v))).collect()
}

/// The small-scene pipelines, one per entry point of
/// [`small_scene_entries`], each made at its first use: a frame needs one
/// of them, and making all 36 at once cost a context's first small-scene
/// renderer half a second on lavapipe.
pub(super) struct SmallKernels {
    device: wgpu::Device,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    entries: Vec<String>,
    pipelines: Vec<OnceLock<Option<wgpu::ComputePipeline>>>,
    /// The latest specialized pipelines, by entry point index and scene
    /// constants, newest last: renderers of one scene and strategy (a
    /// benchmark's seeds and sample counts) share one.
    specialized: Mutex<Vec<SpecializedPipeline>>,
}

/// A pipeline of one small-scene entry point with its constants compiled
/// in (`None`: the driver could not make it).
struct SpecializedPipeline {
    index: usize,
    constants: Vec<u32>,
    pipeline: Option<wgpu::ComputePipeline>,
}

/// How many specialized pipelines a context keeps: each holds its own
/// compiled code (about a megabyte on lavapipe).
const SPECIALIZED_KEPT: usize = 32;

impl SmallKernels {
    pub(super) fn new(device: &wgpu::Device, kernel: &Kernel) -> Self {
        let entries = small_scene_entries();
        let pipelines = entries.iter().map(|_| OnceLock::new()).collect();
        let (module, layout) = (kernel.module.clone(), kernel.trace_pipeline_layout.clone());
        Self { device: device.clone(), module, layout, entries, pipelines, specialized: Mutex::default() }
    }

    /// The pipeline of entry point `index` ([`small_scene_index`]), made
    /// now if it is the first use; `None` where the driver could not make
    /// it: the renderer then traces with the general kernel, which makes
    /// the same image.
    pub(super) fn get(&self, index: usize) -> Option<&wgpu::ComputePipeline> {
        let entry = self.entries.get(index)?;
        self.pipelines[index].get_or_init(|| checked_pipeline(&self.device, &self.module, &self.layout, entry)).as_ref()
    }

    /// The pipeline of entry point `index` with specialization constants
    /// `constants` (`small_scene::scene_constants` of its capacity), made
    /// now unless one of the last few made has the same; `None` where the
    /// driver could not make it (the renderer then runs the unspecialized
    /// pipeline, which makes the same image up to rounding).
    pub(super) fn specialized(&self, index: usize, constants: &[u32]) -> Option<wgpu::ComputePipeline> {
        let entry = self.entries.get(index)?;
        // A poisoned lock only means another renderer's thread panicked
        // while holding it; the list itself is always whole.
        let mut kept = self.specialized.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(k) = kept.iter().find(|k| k.index == index && k.constants == constants) {
            return k.pipeline.clone();
        }
        let words = specialized_spirv(KERNEL_SPV, constants);
        let module = trusted_module(&self.device, "pt-kernel, specialized", std::borrow::Cow::Owned(words));
        let pipeline = checked_pipeline(&self.device, &module, &self.layout, entry);
        if kept.len() == SPECIALIZED_KEPT {
            kept.remove(0);
        }
        kept.push(SpecializedPipeline { index, constants: constants.to_vec(), pipeline: pipeline.clone() });
        pipeline
    }
}

/// SPIR-V's opcodes and decoration that [`specialized_spirv`] reads.
const OP_CONSTANT_TRUE: u32 = 41;
const OP_CONSTANT: u32 = 43;
const OP_SPEC_CONSTANT_TRUE: u32 = 48;
const OP_SPEC_CONSTANT_FALSE: u32 = 49;
const OP_SPEC_CONSTANT: u32 = 50;
const OP_DECORATE: u32 = 71;
const DECORATION_SPEC_ID: u32 = 1;

/// The instructions of SPIR-V module `words` after its 5-word header, as
/// (opcode, the instruction's words).
fn instructions(words: &[u32]) -> impl Iterator<Item = (u32, &[u32])> {
    let mut at = 5.min(words.len());
    std::iter::from_fn(move || {
        let first = *words.get(at)?;
        let len = ((first >> 16) as usize).max(1);
        let inst = words.get(at..at + len)?;
        at += len;
        Some((first & 0xffff, inst))
    })
}

/// The `SpecId` of each specialization constant of `words`, by result id.
fn spec_ids(words: &[u32]) -> std::collections::HashMap<u32, u32> {
    instructions(words)
        .filter(|&(op, inst)| op == OP_DECORATE && inst.len() == 4 && inst[2] == DECORATION_SPEC_ID)
        .map(|(_, inst)| (inst[1], inst[3]))
        .collect()
}

/// The words of SPIR-V module `module` with every specialization
/// constant made a plain constant: `values[id]` for the one decorated
/// `SpecId id` where `values` has it, else its default; the `SpecId`
/// decorations dropped. The small-scene entry points each take the same
/// ids (0 up to their capacity's `constant_words`), so `values` sets
/// those of every entry point: a module made with one capacity's values
/// serves that capacity's entry points only. wgpu gets plain constants
/// either way: nothing depends on how a front end or a driver handles
/// specialization.
pub fn specialized_spirv(module: &[u8], values: &[u32]) -> Vec<u32> {
    let words: Vec<u32> =
        module.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().expect("chunks of 4 bytes"))).collect();
    let spec_ids = spec_ids(&words);
    let mut out = words[..5.min(words.len())].to_vec();
    for (op, inst) in instructions(&words) {
        match op {
            OP_DECORATE if inst.len() == 4 && inst[2] == DECORATION_SPEC_ID => {}
            // (result type, result, value): 32-bit values only take `values`.
            OP_SPEC_CONSTANT => {
                out.push((inst[0] & 0xffff_0000) | OP_CONSTANT);
                out.extend_from_slice(&inst[1..]);
                if let (4, Some(&v)) = (inst.len(), spec_ids.get(&inst[2]).and_then(|&id| values.get(id as usize))) {
                    *out.last_mut().expect("just pushed") = v;
                }
            }
            // OpConstantTrue and OpConstantFalse are 41 and 42, in order.
            OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE => {
                out.push((inst[0] & 0xffff_0000) | (OP_CONSTANT_TRUE + op - OP_SPEC_CONSTANT_TRUE));
                out.extend_from_slice(&inst[1..]);
            }
            _ => out.extend_from_slice(inst),
        }
    }
    out
}

/// [`compute_pipeline`], or `None` where making it raised an error. Each
/// small-scene entry point unrolls the whole scene into one invocation's
/// registers, far more code and state than the general kernel's, and only
/// some drivers have compiled it (docs/ARCHITECTURE.md); a driver that
/// cannot should cost speed, not the render. A browser reports errors only
/// after this call returns, so there the pipeline is taken as made.
fn checked_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
) -> Option<wgpu::ComputePipeline> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        let scopes = [wgpu::ErrorFilter::Internal, wgpu::ErrorFilter::OutOfMemory, wgpu::ErrorFilter::Validation]
            .map(|filter| device.push_error_scope(filter));
        let pipeline = compute_pipeline(device, module, layout, entry);
        // Every scope is popped, innermost first, before any is looked at.
        let errors: Vec<_> = scopes.into_iter().rev().map(|s| pollster::block_on(s.pop())).collect();
        errors.iter().all(Option::is_none).then_some(pipeline)
    }
    #[cfg(target_arch = "wasm32")]
    Some(compute_pipeline(device, module, layout, entry))
}

/// The workgroup shapes the kernel has an `accumulate` entry point for:
/// (entry point, width, height). The first is the default and the only one
/// the renderers use; the others exist for `pathtracer bench` to time.
pub const WORKGROUP_SHAPES: [(&str, u32, u32); 4] = [
    ("accumulate", 8, 8),
    ("accumulate_16x4_groups", 16, 4),
    ("accumulate_32x2_groups", 32, 2),
    ("accumulate_4x4_groups", 4, 4),
];

pub(super) fn compute_pipeline(
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
    pub(super) fn new(device: &wgpu::Device) -> Self {
        let module = kernel_module(device);
        // wgpu matches storage access exactly, and the accumulation buffer is
        // read-write for `accumulate` but read-only for `display`: one
        // layout per entry point, each with the bindings it uses.
        let trace_layout = bind_group_layout(
            device,
            "accumulate",
            &[uniform_entry::<Geometry>(GEOMETRY), storage_entry(ACCUM, false), storage_entry(NON_FINITE, false)],
        );
        let display_layout =
            bind_group_layout(device, "display", &[storage_entry(ACCUM, true), storage_entry(DISPLAY, false)]);
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
/// Its specialization constants are set to their defaults (zeros: the
/// small-scene entry points then read the scene from the buffers).
pub(super) fn kernel_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    trusted_module(device, "pt-kernel", std::borrow::Cow::Owned(kernel_words()))
}

/// The kernel module as wgpu gets it: [`KERNEL_SPV`] with its
/// specialization constants at their defaults ([`specialized_spirv`]).
pub fn kernel_words() -> Vec<u32> {
    specialized_spirv(KERNEL_SPV, &[])
}

/// A shader module of the kernel's words, without naga's runtime checks
/// ([`kernel_module`] says why that is sound).
fn trusted_module(device: &wgpu::Device, label: &str, words: std::borrow::Cow<'_, [u32]>) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor { label: Some(label), source: wgpu::ShaderSource::SpirV(words) };
    // SAFETY: see `kernel_module`: the kernel indexes only through Rust's
    // bounds checks and has no unbounded loop, which is what the unchecked
    // options ask of the caller.
    unsafe { device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked()) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_core::small_scene::constant_words;

    /// A small-scene pipeline that cannot be made is `None`, its error
    /// caught there: the context reports no failure, and the other entry
    /// points are made as before.
    #[test]
    fn a_small_scene_pipeline_that_cannot_be_made_is_none() {
        let ctx = crate::gpu::GpuContext::new().expect("GPU tests need a Vulkan adapter (lavapipe in CI)");
        let mut small = SmallKernels::new(&ctx.device, ctx.kernel());
        small.entries[0] = "no_such_entry_point".into();
        assert!(small.get(0).is_none());
        assert!(small.get(1).is_some());
        ctx.wait().expect("the error was caught where the pipeline was made");
    }

    /// The renderer's index of a (capacity, variant) pair finds that
    /// pair's entry point among the pipelines made in
    /// `small_scene_entries`' order, for every pair, and a frame picks the
    /// entry points without the connections', the glow lobe's or the
    /// roulette's code exactly where it uses none of it.
    /// The kernel's specialization constants are the small-scene entry
    /// points' scene constants, ids 0 up to the largest capacity's count,
    /// each once (the entry points share them). Specialized, each is a
    /// plain constant with its value (or its default, 0, past the values
    /// given), and no specialization constant or `SpecId` is left.
    #[test]
    fn specialization_constants_become_plain_constants() {
        let raw: Vec<u32> = KERNEL_SPV.chunks_exact(4).map(|b| u32::from_le_bytes(b.try_into().unwrap())).collect();
        let ids = spec_ids(&raw);
        let mut sorted: Vec<u32> = ids.values().copied().collect();
        sorted.sort_unstable();
        let largest = SMALL_SCENE_SIZES.iter().map(|&(w, s)| constant_words(w, s)).max().unwrap();
        assert_eq!(sorted, (0..largest as u32).collect::<Vec<_>>());
        let values: Vec<u32> = (0..100).map(|i| 1000 + i).collect();
        let out = specialized_spirv(KERNEL_SPV, &values);
        assert_eq!(out.len(), raw.len() - 4 * ids.len(), "only the decorations dropped");
        assert!(spec_ids(&out).is_empty());
        let mut seen = 0;
        for (op, inst) in instructions(&out) {
            assert!(!(OP_SPEC_CONSTANT_TRUE..=52).contains(&op), "opcode {op} left");
            if let Some(&id) = ids.get(&inst[2.min(inst.len() - 1)]).filter(|_| op == OP_CONSTANT) {
                assert_eq!(inst[3], values.get(id as usize).copied().unwrap_or(0), "SpecId {id}");
                seen += 1;
            }
        }
        assert_eq!(seen, ids.len());
        // Unchanged but for the constants: the defaults give the module
        // wgpu gets.
        assert_eq!(kernel_words().len(), out.len());
    }

    /// The notice names what keeps a scene off the small-scene kernel:
    /// nothing for a scene of 16 spheres, the count for a 17th, the wall
    /// for a panel that can shadow the light where the scene is read from
    /// the buffers (compiled in, the kernel holds it). A renderer that asks
    /// for the general kernel gets no notice.
    #[test]
    fn a_misfit_says_why() {
        use crate::gpu::GpuRenderer;
        use crate::scene::{NamedSphere, NamedWall, Scene};
        use pt_core::glam::Vec3;
        let misfit = |scene: &Scene, compiled_in| {
            let settings = scene.render;
            small_scene_misfit(&scene.frame_params(&settings, 1, 0), &scene.geometry().unwrap(), compiled_in)
        };
        let mut scene = Scene::default_scene();
        assert_eq!(misfit(&scene, false), None);
        for k in 0..15 {
            let at = Vec3::new(-0.75 + 0.25 * (k % 7) as f32, 1.2, 0.6 - 0.25 * (k / 7) as f32);
            let sphere = pt_core::Sphere::new(at, 0.08, Vec3::splat(0.5));
            scene.spheres.push(NamedSphere { name: format!("extra {k}"), sphere });
            let want = (k == 14).then(|| "17 spheres (the small-scene kernel holds 16)".to_string());
            assert_eq!(misfit(&scene, false), want, "{} spheres", scene.spheres.len());
            assert_eq!(misfit(&scene, true), want, "{} spheres", scene.spheres.len());
        }
        let notice = GpuRenderer::general_kernel_notice(&scene, TraceKernel::Specialized);
        assert!(notice.is_some_and(|n| n.starts_with("note: the general kernel traces this scene")));
        assert_eq!(GpuRenderer::general_kernel_notice(&scene, TraceKernel::General), None);
        let mut panel = Scene::default_scene();
        let wall = pt_core::Wall::new(Vec3::new(-0.5, 1.0, -0.5), Vec3::X, Vec3::new(0.0, 0.2, 0.6), Vec3::splat(0.5));
        panel.walls.push(NamedWall { name: "panel".into(), wall });
        assert!(misfit(&panel, false).is_some_and(|why| why.starts_with("a wall that can block the light")));
        assert_eq!(misfit(&panel, true), None);
    }

    #[test]
    fn small_scene_index_finds_its_entry_point() {
        use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAG_NEE, FLAG_SOBOL, FLAG_SOBOL_DEEP, FLAGS_DEFAULT};
        let entries = small_scene_entries();
        assert_eq!(entries.len(), SMALL_SCENE_SIZES.len() * 18);
        for (i, &size) in SMALL_SCENE_SIZES.iter().enumerate() {
            for v in SmallVariant::all() {
                assert_eq!(entries[small_scene_index(i, v)], small_scene_entry(size, v));
            }
        }
        let mut sorted = entries.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), entries.len(), "every variant has its own entry point");
        let deep = FLAGS_DEFAULT | FLAG_SOBOL | FLAG_SOBOL_DEEP;
        // Roulette from the second bounce of five: it acts.
        let frame = |flags| FrameParams { flags, max_bounces: 5, rr_start: 2, ..Default::default() };
        let entry = |flags| small_scene_entry((5, 2), SmallVariant::of(&frame(flags)));
        assert_eq!(entry(deep | FLAG_CONNECT), "accumulate_small_5w_2s_sobol_deep");
        assert_eq!(entry((deep | FLAG_CONNECT) & !FLAG_GLOW), "accumulate_small_5w_2s_sobol_deep");
        assert_eq!(entry(deep), "accumulate_small_5w_2s_sobol_deep_unconnected");
        assert_eq!(entry(deep & !FLAG_GLOW), "accumulate_small_5w_2s_sobol_deep_unconnected_noglow");
        let no_nee = (deep | FLAG_CONNECT) & !FLAG_NEE;
        assert_eq!(
            small_scene_entry((8, 16), SmallVariant::of(&frame(no_nee))),
            "accumulate_small_8w_16s_sobol_deep_unconnected"
        );
        // Roulette from the fifth bounce of five, with NEE and a black
        // background: no path draws a direction at its fifth vertex.
        let last = FrameParams { rr_start: 5, ..frame(deep) };
        assert_eq!(
            small_scene_entry((5, 2), SmallVariant::of(&last)),
            "accumulate_small_5w_2s_sobol_deep_unconnected_noroulette"
        );
    }

    /// With the scene compiled in, the small-scene path loop renders the
    /// general loops' samples bit for bit where walls can block the light:
    /// the default light raised through the ceiling, and the large sphere
    /// sunk into the floor (whose cap under it, seen through the open
    /// front, the floor hides from the light). Read from the buffers, with
    /// no wall in its shadow tests, the same loop renders other samples
    /// under the raised light: the comparison can fail. (Paths that reach
    /// the sunk sphere's cap are too rare to show in 16 samples of 256
    /// pixels.)
    #[test]
    fn compiled_in_walls_that_block_the_light_keep_the_samples() {
        use pt_core::integrator::{render_pixel, render_pixel_small, render_pixel_specialized};
        use pt_core::params::{FLAG_CONNECT, FLAGS_DEFAULT};
        use pt_core::sampler::SobolSampler;
        use pt_core::small_scene::{SmallScene, scene_constants};

        use crate::scene::{RenderSettings, Scene};
        let mut through_ceiling = Scene::default_scene();
        through_ceiling.light.center.y = 1.9;
        let mut sunk = Scene::default_scene();
        sunk.spheres[0].sphere.center.y -= 0.05;
        for (scene, shows) in [(through_ceiling, true), (sunk, false)] {
            let geometry = scene.geometry().unwrap();
            let settings = RenderSettings { width: 16, height: 16, ..scene.render };
            for flags in [FLAGS_DEFAULT, FLAGS_DEFAULT | FLAG_CONNECT] {
                let params = FrameParams { flags, ..scene.frame_params(&settings, 16, 7) };
                assert!(!SmallScene::<5, 2>::fits(&params, &geometry));
                assert!(SmallScene::<5, 2>::fits_compiled(&params, &geometry));
                let constants: [u32; constant_words(5, 2)] =
                    scene_constants::<5, 2>(&params, &geometry).try_into().unwrap();
                let mut differ = 0;
                for (x, y) in (0..16).flat_map(|y| (0..16).map(move |x| (x, y))) {
                    let want = render_pixel(x, y, &params, &geometry);
                    let got = render_pixel_specialized::<SobolSampler, 5, 2, true, true, true, { constant_words(5, 2) }>(
                        x, y, &params, &geometry, &constants,
                    );
                    assert_eq!(got, want, "flags {flags:#x}, pixel ({x}, {y})");
                    differ += (render_pixel_small::<SobolSampler, 5, 2, true, true, true>(x, y, &params, &geometry)
                        != want) as u32;
                }
                assert_eq!(differ > 0, shows, "flags {flags:#x}: {differ} pixels change without the walls' tests");
            }
        }
    }

    /// Where Russian roulette can act and where it cannot: a path draws
    /// a direction after each of its first `max_bounces - 1` vertices, and
    /// at its last one only without NEE or with a background that shows.
    #[test]
    fn roulette_acts_where_a_path_draws_past_its_start() {
        use pt_core::glam::Vec3;
        use pt_core::params::{FLAG_NEE, FLAGS_DEFAULT};
        let frame =
            |rr_start, max_bounces| FrameParams { flags: FLAGS_DEFAULT, rr_start, max_bounces, ..Default::default() };
        assert!(roulette_acts(&frame(4, 5)));
        assert!(!roulette_acts(&frame(5, 5)));
        assert!(!roulette_acts(&frame(6, 5)));
        assert!(roulette_acts(&frame(5, 16)));
        assert!(roulette_acts(&FrameParams { flags: FLAGS_DEFAULT & !FLAG_NEE, ..frame(5, 5) }));
        assert!(roulette_acts(&FrameParams { background: Vec3::splat(0.1), ..frame(5, 5) }));
        assert!(!roulette_acts(&FrameParams { background: Vec3::splat(0.1), ..frame(6, 5) }));
    }

    /// Where the roulette cannot act, the path loop without its code
    /// (`render_pixel_small` with `ROULETTE` false) returns the samples of
    /// the full loop bit for bit, with every sampler and optional code the
    /// kernel has, on the default scene at its bounce limit and roulette
    /// start (5 and 5). Where it acts (from the second bounce), leaving it
    /// out changes the samples: the comparison can fail.
    #[test]
    fn leaving_out_the_roulette_where_it_cannot_act_keeps_the_samples() {
        use pt_core::integrator::{render_pixel, render_pixel_small};
        use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAG_SOBOL, FLAG_SOBOL_DEEP, FLAGS_DEFAULT};
        use pt_core::rng::Rng;
        use pt_core::sampler::SobolSampler;
        use pt_core::small_scene::SmallScene;
        use pt_core::{FrameParams, PixelSamples};

        use crate::scene::{RenderSettings, Scene};
        let scene = Scene::default_scene();
        let geometry = scene.geometry().unwrap();
        let settings = RenderSettings { width: 16, height: 16, spp: 0, max_bounces: 5, rr_start: 5 };
        let base = scene.frame_params(&settings, 16, 7);
        assert!(SmallScene::<5, 2>::fits(&base, &geometry));
        type Render = fn(u32, u32, &FrameParams, &Geometry) -> PixelSamples;
        let d = FLAGS_DEFAULT;
        let forms: [(u32, Render); 6] = [
            (d & !FLAG_SOBOL, render_pixel_small::<Rng, 5, 2, false, true, false>),
            ((d & !FLAG_SOBOL) | FLAG_CONNECT, render_pixel_small::<Rng, 5, 2, true, true, false>),
            (d, render_pixel_small::<SobolSampler, 5, 2, false, true, false>),
            (d & !FLAG_GLOW, render_pixel_small::<SobolSampler, 5, 2, false, false, false>),
            (
                d | FLAG_SOBOL_DEEP | FLAG_CONNECT,
                render_pixel_small::<SobolSampler<{ u32::MAX }>, 5, 2, true, true, false>,
            ),
            (d | FLAG_SOBOL_DEEP, render_pixel_small::<SobolSampler<{ u32::MAX }>, 5, 2, false, true, false>),
        ];
        for (flags, render) in forms {
            let params = FrameParams { flags, ..base };
            assert!(!roulette_acts(&params));
            for (x, y) in (0..16).map(|i| (i, (5 * i) % 16)) {
                assert_eq!(
                    render(x, y, &params, &geometry),
                    render_pixel(x, y, &params, &geometry),
                    "flags {flags:#x}, pixel ({x}, {y})"
                );
            }
            let early = FrameParams { rr_start: 2, ..params };
            assert!(roulette_acts(&early));
            let differ =
                (0..16).filter(|&x| render(x, 8, &early, &geometry) != render_pixel(x, 8, &early, &geometry)).count();
            assert!(
                differ > 8,
                "flags {flags:#x}: {differ} of 16 pixels differ without the roulette from the second bounce"
            );
        }
    }
}
