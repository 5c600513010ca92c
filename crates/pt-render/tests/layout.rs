//! Host and kernel agree on the layout of every GPU struct: the offsets and
//! sizes that rust-gpu wrote into the SPIR-V module (read back with naga)
//! are the host's `offset_of!` and `size_of`. A field added on one side
//! only, or padding that differs, fails here instead of corrupting a frame.

use std::mem::{offset_of, size_of};

use naga::{Handle, Module, Type, TypeInner, front::spv};
use pt_core::{AccumPixel, Camera, FrameParams, Sphere, SphereLight, Wall};
use pt_render::KERNEL_SPV;

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

/// Element struct and stride of the runtime array in the block at `binding`.
fn array_element(m: &Module, binding: u32) -> (Handle<Type>, u32) {
    match &m.types[member(m, bound(m, binding), 0)].inner {
        TypeInner::Array { base, stride, .. } => (*base, *stride),
        other => panic!("binding {binding}: expected an array, found {other:?}"),
    }
}

macro_rules! host_layout {
    ($t:ty { $($f:ident),* }) => {
        (size_of::<$t>() as u32, vec![$(offset_of!($t, $f) as u32),*])
    };
}

fn wall_layout() -> (u32, Vec<u32>) {
    host_layout!(Wall { corner, _pad0, edge_u, _pad1, edge_v, _pad2, normal, _pad3, w, _pad4, albedo, _pad5 })
}

#[test]
fn frame_params_match_the_uniform_block() {
    let m = module();
    let params = member(&m, bound(&m, 0), 0);
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
            sample_offset
        })
    );
    assert_eq!(
        layout(&m, member(&m, params, 0)),
        host_layout!(Camera { position, _pad0, forward, _pad1, right, _pad2, up, _pad3 })
    );
    assert_eq!(layout(&m, member(&m, params, 1)), host_layout!(SphereLight { center, radius, radiance, _pad }));
}

#[test]
fn walls_match_the_storage_array() {
    let m = module();
    let (wall, stride) = array_element(&m, 1);
    assert_eq!(stride as usize, size_of::<Wall>());
    assert_eq!(layout(&m, wall), wall_layout());
}

#[test]
fn spheres_match_the_storage_array() {
    let m = module();
    let (sphere, stride) = array_element(&m, 2);
    assert_eq!(stride as usize, size_of::<Sphere>());
    assert_eq!(layout(&m, sphere), host_layout!(Sphere { center, radius, albedo, _pad }));
}

#[test]
fn accumulation_pixels_match_the_storage_array() {
    let m = module();
    let (px, stride) = array_element(&m, 3);
    assert_eq!(stride as usize, size_of::<AccumPixel>());
    assert_eq!(layout(&m, px), host_layout!(AccumPixel { sum, samples, compensation, non_finite }));
}

#[test]
fn host_layouts_are_the_documented_ones() {
    // Exact numbers, so that a change of layout is a visible decision.
    assert_eq!(wall_layout(), (96, vec![0, 12, 16, 28, 32, 44, 48, 60, 64, 76, 80, 92]));
    assert_eq!(size_of::<FrameParams>(), 160);
    assert_eq!(size_of::<Camera>(), 64);
    assert_eq!(size_of::<SphereLight>(), 32);
    assert_eq!(size_of::<Sphere>(), 32);
    assert_eq!(size_of::<AccumPixel>(), 32);
}
