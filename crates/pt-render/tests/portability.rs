//! The embedded kernel runs on every backend wgpu serves: wgpu reads the
//! SPIR-V with naga and writes it out again as MSL on Metal, HLSL on DX12 and
//! WGSL in a browser. Each entry point is translated here as wgpu would, so
//! that a construct one of those writers rejects fails on this machine,
//! without a Mac, a Windows machine or a browser. WGSL output is read back
//! and validated again; MSL and HLSL have no validator short of Apple's and
//! Microsoft's compilers, so for them the check is naga's: the module
//! validates with that backend's capabilities and the writer accepts it.

use naga::back::{hlsl, msl, wgsl};
use naga::front::spv;
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga::{Module, ShaderStage};
use pt_render::gpu::kernel_words;

/// The kernel as wgpu reads it: its words as the renderer passes them
/// (specialization constants made plain), with
/// `wgpu::ShaderSource::SpirV`'s options.
fn kernel() -> Module {
    let options =
        spv::Options { adjust_coordinate_space: false, strict_capabilities: true, block_ctx_dump_prefix: None };
    spv::Frontend::new(kernel_words().into_iter(), &options).parse().expect("naga reads the kernel")
}

fn validate(module: &Module, capabilities: Capabilities, backend: &str) -> ModuleInfo {
    Validator::new(ValidationFlags::all(), capabilities)
        .validate(module)
        .unwrap_or_else(|e| panic!("the kernel does not validate for {backend}: {e:?}"))
}

/// (stage, name) of every entry point, checked to be the full set.
fn entry_points(module: &Module) -> Vec<(ShaderStage, String)> {
    let eps: Vec<_> = module.entry_points.iter().map(|ep| (ep.stage, ep.name.clone())).collect();
    // Case: the module's entry points are the ones the renderer and viewer
    // create pipelines for (the small-scene ones by the names the GPU
    // renderer builds); a renamed or dropped one fails here too.
    let mut names: Vec<&str> = eps.iter().map(|(_, n)| n.as_str()).collect();
    names.sort();
    let small = pt_render::gpu::small_scene_entries();
    let mut want: Vec<&str> =
        ["accumulate", "accumulate_16x4_groups", "accumulate_32x2_groups", "accumulate_4x4_groups"]
            .into_iter()
            .chain(small.iter().map(String::as_str))
            .chain(["blit_fs", "blit_vs", "display"])
            .collect();
    want.sort();
    assert_eq!(names, want);
    // Three capacities, three samplers, three forms of optional code, with
    // and without the roulette's code.
    assert_eq!(small.len(), 54);
    assert!(names.contains(&"accumulate_small_5w_2s_sobol_unconnected_noglow_noroulette"));
    eps
}

/// Metal: MSL 2.4 (macOS 12, iOS 15), what wgpu's Metal backend targets on
/// current systems.
#[test]
fn every_entry_point_translates_to_msl() {
    let module = kernel();
    let info = validate(&module, msl::supported_capabilities(), "MSL");
    for (stage, name) in entry_points(&module) {
        let options = msl::Options { lang_version: (2, 4), force_loop_bounding: false, ..Default::default() };
        let pipeline = msl::PipelineOptions { entry_point: Some((stage, name.clone())), ..Default::default() };
        let (source, _) = msl::write_string(&module, &info, &options, &pipeline)
            .unwrap_or_else(|e| panic!("MSL writer rejects entry point {name}: {e:?}"));
        assert!(source.contains(&name), "the MSL of {name} does not define it");
    }
}

/// DX12: HLSL shader model 6.0, the lowest wgpu's DX12 backend compiles for
/// with DXC.
#[test]
fn every_entry_point_translates_to_hlsl() {
    let module = kernel();
    let info = validate(&module, hlsl::supported_capabilities(), "HLSL");
    for (stage, name) in entry_points(&module) {
        let options =
            hlsl::Options { shader_model: hlsl::ShaderModel::V6_0, force_loop_bounding: false, ..Default::default() };
        let pipeline = hlsl::PipelineOptions { entry_point: Some((stage, name.clone())) };
        let mut source = String::new();
        hlsl::Writer::new(&mut source, &options, &pipeline)
            .write(&module, &info, None)
            .unwrap_or_else(|e| panic!("HLSL writer rejects entry point {name}: {e:?}"));
        assert!(source.contains(&name), "the HLSL of {name} does not define it");
    }
}

/// WebGPU: the WGSL naga writes parses again and validates with WebGPU's
/// base capabilities (no extensions), every entry point under its own name
/// (a browser's pipeline looks it up by that name; naga renames one that
/// ends in a digit).
#[test]
fn wgsl_round_trips_with_webgpu_capabilities() {
    let module = kernel();
    let info = validate(&module, Capabilities::empty(), "WGSL (WebGPU)");
    let source = wgsl::write_string(&module, &info, wgsl::WriterFlags::empty())
        .unwrap_or_else(|e| panic!("WGSL writer rejects the kernel: {e:?}"));
    let reparsed = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("naga cannot read its own WGSL: {}", e.emit_to_string(&source)));
    validate(&reparsed, Capabilities::empty(), "WGSL read back");
    assert_eq!(entry_points(&reparsed), entry_points(&module));

    // Browsers read a decimal literal exactly: `3.4028235e38f`, the
    // shortest form that reads back as f32::MAX in Rust, is above f32::MAX
    // and Chromium rejects the module ("value cannot be represented as
    // 'f32'"). naga accepts it, so the check is here.
    let too_large: Vec<&str> =
        f32_literals(&source).filter(|l| l.parse::<f64>().unwrap().abs() > f32::MAX as f64).collect();
    assert!(too_large.is_empty(), "f32 literals a browser rejects: {too_large:?} (use a finite bound below f32::MAX)");
}

/// The f32 literals of WGSL source (`1.5f`, `3e38f`), without the suffix.
fn f32_literals(source: &str) -> impl Iterator<Item = &str> {
    let bytes = source.as_bytes();
    let mut i = 0;
    std::iter::from_fn(move || {
        while i < bytes.len() {
            let start = i;
            let starts_token = start == 0 || !(bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_');
            if !(starts_token && bytes[i].is_ascii_digit()) {
                i += 1;
                continue;
            }
            while i < bytes.len() && (bytes[i].is_ascii_digit() || matches!(bytes[i], b'.' | b'e' | b'E'))
                || (i > start && matches!(bytes[i - 1], b'e' | b'E') && matches!(bytes[i], b'+' | b'-'))
            {
                i += 1;
            }
            if bytes.get(i) == Some(&b'f') {
                i += 1;
                return Some(&source[start..i - 1]);
            }
        }
        None
    })
}

#[test]
fn f32_literals_are_found_in_wgsl() {
    let found: Vec<_> = f32_literals("let a = 1.5f + x2f * 3e38f - 2.5e-3f; let b = 7u; let c = 1f;").collect();
    assert_eq!(found, ["1.5", "3e38", "2.5e-3", "1"]);
}
