//! The kernel module and its compute pipelines.

use pt_core::Geometry;
use pt_core::bsdf::glow_probability;
use pt_core::integrator::{SamplerKind, connects};
use pt_core::small_scene::SMALL_SCENE_SIZES;

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
    /// scenes that fit none use `General`. The default
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
/// sampler and the optional code.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) struct SmallVariant {
    pub(super) sampler: SamplerKind,
    pub(super) code: SmallCode,
}

impl SmallVariant {
    /// Every variant, in the kernel's order: samplers in
    /// `SamplerKind::ALL`'s order, each with every [`SmallCode`].
    fn all() -> impl Iterator<Item = SmallVariant> {
        SamplerKind::ALL.into_iter().flat_map(|sampler| SmallCode::ALL.map(|code| SmallVariant { sampler, code }))
    }

    /// The variant integrator `flags` need: their sampler, the connections'
    /// code only where they make connections, and the glow lobe's only
    /// where they have it or the connections (leaving code out where the
    /// flags use none of it renders the same samples, faster on lavapipe,
    /// which would run it masked).
    pub(super) fn of(flags: u32) -> Self {
        let code = if connects(flags) {
            SmallCode::Connected
        } else if glow_probability(flags) > 0.0 {
            SmallCode::Unconnected
        } else {
            SmallCode::Bare
        };
        Self { sampler: SamplerKind::of(flags), code }
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
    format!("accumulate_small_{walls}w_{spheres}s_{sampler}{}", variant.code.suffix())
}

/// Index of the small-scene pipeline of capacity `size` (an index in
/// `SMALL_SCENE_SIZES`) and `variant` in [`small_scene_entries`]' order.
pub(super) fn small_scene_index(size: usize, variant: SmallVariant) -> usize {
    let per_size = SamplerKind::ALL.len() * SmallCode::ALL.len();
    size * per_size + variant.sampler as usize * SmallCode::ALL.len() + variant.code as usize
}

/// Every small-scene entry point: capacities in `SMALL_SCENE_SIZES`' order,
/// each with every variant in `SmallVariant::ALL`'s order.
pub fn small_scene_entries() -> Vec<String> {
    SMALL_SCENE_SIZES.iter().flat_map(|&size| SmallVariant::all().map(move |v| small_scene_entry(size, v))).collect()
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
pub(super) fn kernel_module(device: &wgpu::Device) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor { label: Some("pt-kernel"), source: wgpu::util::make_spirv(KERNEL_SPV) };
    // SAFETY: see above: the kernel indexes only through Rust's bounds
    // checks and has no unbounded loop, which is what the unchecked
    // options ask of the caller.
    unsafe { device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The renderer's index of a (capacity, variant) pair finds that
    /// pair's entry point among the pipelines made in
    /// `small_scene_entries`' order, for every pair, and the flags pick
    /// the entry points without the connections' or the glow lobe's code
    /// exactly where they use none of it.
    #[test]
    fn small_scene_index_finds_its_entry_point() {
        use pt_core::params::{FLAG_CONNECT, FLAG_GLOW, FLAG_NEE, FLAG_SOBOL, FLAG_SOBOL_DEEP, FLAGS_DEFAULT};
        let entries = small_scene_entries();
        assert_eq!(entries.len(), SMALL_SCENE_SIZES.len() * 9);
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
        let entry = |flags| small_scene_entry((5, 2), SmallVariant::of(flags));
        assert_eq!(entry(deep | FLAG_CONNECT), "accumulate_small_5w_2s_sobol_deep");
        assert_eq!(entry((deep | FLAG_CONNECT) & !FLAG_GLOW), "accumulate_small_5w_2s_sobol_deep");
        assert_eq!(entry(deep), "accumulate_small_5w_2s_sobol_deep_unconnected");
        assert_eq!(entry(deep & !FLAG_GLOW), "accumulate_small_5w_2s_sobol_deep_unconnected_noglow");
        let no_nee = (deep | FLAG_CONNECT) & !FLAG_NEE;
        assert_eq!(
            small_scene_entry((8, 4), SmallVariant::of(no_nee)),
            "accumulate_small_8w_4s_sobol_deep_unconnected"
        );
    }
}
