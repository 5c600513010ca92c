//! Host and kernel agree on the layout of every GPU struct: the offsets and
//! sizes that rust-gpu wrote into the SPIR-V module (read back with naga)
//! are the host's `offset_of!` and `size_of`. A field added on one side
//! only, or padding that differs, fails here instead of corrupting a frame.

use std::mem::{offset_of, size_of};

use naga::ArraySize;
use naga::{Handle, Module, Type, TypeInner, front::spv};
use pt_core::geometry::{MAX_SPHERES, MAX_WALLS};
use pt_core::{AccumPixel, Camera, FrameParams, Geometry, Sphere, SphereLight, Tile, Wall};
use pt_render::KERNEL_SPV;
use pt_render::gpu::bindings::{ACCUM, DISPLAY, GEOMETRY, NON_FINITE, PARAMS};

fn module() -> Module {
    spv::parse_u8_slice(KERNEL_SPV, &spv::Options::default()).expect("naga reads the kernel")
}

/// (size, member offsets) of a struct type.
fn layout(m: &Module, ty: Handle<Type>) -> (u32, Vec<u32>) {
    match &m.types[ty].inner {
        TypeInner::Struct { members, span } => (*span, members.iter().map(|x| x.offset).collect()),
        other => panic!("expected a struct, found {other:?}"),
    }
}

/// The type of member `i` of struct `ty`.
fn member(m: &Module, ty: Handle<Type>, i: usize) -> Handle<Type> {
    match &m.types[ty].inner {
        TypeInner::Struct { members, .. } => members[i].ty,
        other => panic!("expected a struct, found {other:?}"),
    }
}

/// The block type bound at (group 0, `binding`).
fn bound(m: &Module, binding: u32) -> Handle<Type> {
    m.global_variables
        .iter()
        .find(|(_, g)| g.binding.as_ref().is_some_and(|b| b.group == 0 && b.binding == binding))
        .map(|(_, g)| g.ty)
        .unwrap_or_else(|| panic!("no global at binding {binding}"))
}

/// Element, stride and length (`None`: runtime-sized) of array type `ty`.
fn array(m: &Module, ty: Handle<Type>) -> (Handle<Type>, u32, Option<u32>) {
    match &m.types[ty].inner {
        TypeInner::Array { base, stride, size } => {
            let len = match size {
                ArraySize::Constant(n) => Some(n.get()),
                _ => None,
            };
            (*base, *stride, len)
        }
        other => panic!("expected an array, found {other:?}"),
    }
}

macro_rules! host_layout {
    ($t:ty { $($f:ident),* }) => {
        (size_of::<$t>() as u32, vec![$(offset_of!($t, $f) as u32),*])
    };
}

fn wall_layout() -> (u32, Vec<u32>) {
    host_layout!(Wall {
        corner,
        _pad0,
        edge_u,
        _pad1,
        edge_v,
        _pad2,
        normal,
        enclosure_side,
        coord_u,
        _pad4,
        coord_v,
        _pad5,
        albedo,
        _pad6
    })
}

#[test]
fn frame_params_match_the_uniform_block() {
    let m = module();
    let params = member(&m, bound(&m, PARAMS), 0);
    assert_eq!(
        layout(&m, params),
        host_layout!(FrameParams {
            camera,
            light,
            background,
            exposure,
            width,
            height,
            frame,
            samples_per_frame,
            max_bounces,
            rr_start,
            seed,
            wall_count,
            sphere_count,
            tonemap,
            flags,
            sample_offset,
            tile
        })
    );
    assert_eq!(layout(&m, member(&m, params, 16)), host_layout!(Tile { x, y, width, height }));
    assert_eq!(
        layout(&m, member(&m, params, 0)),
        host_layout!(Camera { position, _pad0, forward, _pad1, right, _pad2, up, _pad3 })
    );
    assert_eq!(layout(&m, member(&m, params, 1)), host_layout!(SphereLight { center, radius, radiance, _pad }));
}

#[test]
fn geometry_matches_the_uniform_block() {
    let m = module();
    let geometry = member(&m, bound(&m, GEOMETRY), 0);
    assert_eq!(layout(&m, geometry), host_layout!(Geometry { walls, spheres }));

    let (wall, stride, len) = array(&m, member(&m, geometry, 0));
    assert_eq!((stride as usize, len), (size_of::<Wall>(), Some(MAX_WALLS as u32)));
    assert_eq!(layout(&m, wall), wall_layout());

    let (sphere, stride, len) = array(&m, member(&m, geometry, 1));
    assert_eq!((stride as usize, len), (size_of::<Sphere>(), Some(MAX_SPHERES as u32)));
    assert_eq!(layout(&m, sphere), host_layout!(Sphere { center, radius, albedo, _pad }));
}

#[test]
fn accumulation_pixels_match_the_storage_array() {
    let m = module();
    let (px, stride, len) = array(&m, member(&m, bound(&m, ACCUM), 0));
    assert_eq!(len, None);
    assert_eq!(stride as usize, size_of::<AccumPixel>());
    assert_eq!(layout(&m, px), host_layout!(AccumPixel { sum, samples, compensation, non_finite }));
}

#[test]
fn host_layouts_are_the_documented_ones() {
    // Exact numbers, so that a change of layout is a visible decision.
    assert_eq!(wall_layout(), (112, vec![0, 12, 16, 28, 32, 44, 48, 60, 64, 76, 80, 92, 96, 108]));
    assert_eq!(size_of::<FrameParams>(), 176);
    assert_eq!(size_of::<Camera>(), 64);
    assert_eq!(size_of::<SphereLight>(), 32);
    assert_eq!(size_of::<Sphere>(), 32);
    assert_eq!(size_of::<AccumPixel>(), 32);
    assert_eq!(size_of::<Geometry>(), 96 * 112 + 128 * 32);
}

/// A type as a struct's size, `[element]`, `u32` or `atomic u32`. naga
/// keeps no type names, so structs are told apart by size here; the tests
/// above check their members.
fn describe(m: &Module, ty: Handle<Type>) -> String {
    match &m.types[ty].inner {
        TypeInner::Struct { span, .. } => format!("struct of {span} bytes"),
        TypeInner::Array { base, .. } => format!("[{}]", describe(m, *base)),
        TypeInner::Scalar(s) if *s == naga::Scalar::U32 => "u32".into(),
        TypeInner::Atomic(s) if *s == naga::Scalar::U32 => "atomic u32".into(),
        other => format!("{other:?}"),
    }
}

/// What the block struct rust-gpu wraps around every binding holds.
fn bound_type(m: &Module, ty: Handle<Type>) -> String {
    describe(m, member(m, ty, 0))
}

/// Case: every binding the kernel declares is one the host names in
/// `gpu::bindings`, with the type and address space the host binds there;
/// a binding renumbered on one side only fails here.
#[test]
fn every_kernel_binding_is_the_one_the_host_names() {
    let m = module();
    let found: std::collections::BTreeSet<(u32, bool, String)> = m
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            assert_eq!(b.group, 0, "the host binds group 0 only");
            let uniform = matches!(g.space, naga::AddressSpace::Uniform);
            Some((b.binding, uniform, bound_type(&m, g.ty)))
        })
        .collect();
    let block = |size: usize| format!("struct of {size} bytes");
    let expected = [
        (PARAMS, false, block(size_of::<FrameParams>())),
        (GEOMETRY, true, block(size_of::<Geometry>())),
        (ACCUM, false, format!("[{}]", block(size_of::<AccumPixel>()))),
        (DISPLAY, false, "[u32]".to_string()),
        // `accumulate` adds to it atomically.
        (NON_FINITE, false, "[atomic u32]".to_string()),
    ];
    assert_eq!(found, expected.into_iter().collect());
}
