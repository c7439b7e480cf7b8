//! The scene layout is defined once in Rust (`#[repr(C)]` + bytemuck) and declared again in
//! WGSL; this test compares every shared struct's size, field names and field offsets with
//! naga's reflection of the WGSL declarations, so the two cannot drift apart.

use hexray::accel::hash_grid::GridParams;
use hexray::gpu::frame::{Frame, PixelSums};
use hexray::gpu::radiosity::RadiosityParams;
use hexray::gpu::shader::{source, validate, ArrayLengths, Residency};
use hexray::layout::{BvhNode, Emitter, Material, PlanarMirror, Sphere, Triangle};
use hexray::transport::camera::Camera;
use hexray::transport::patches::{Patch, PatchGrid};
use hexray::transport::subpath::{LightVertex, PhotonRecord};
use std::mem::{offset_of, size_of};

macro_rules! rust_layout {
    ($t:ident { $($f:ident),* $(,)? }) => {
        (
            stringify!($t),
            size_of::<$t>() as u32,
            vec![$((stringify!($f).to_string(), offset_of!($t, $f) as u32)),*],
        )
    };
}

fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let fields = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect();
                return (*span, fields);
            }
        }
    }
    panic!("struct {name} is not declared in the WGSL");
}

#[test]
fn shared_structs_match_their_wgsl_declarations_field_by_field() {
    let (module, _) = validate(&source(Residency::Storage, ArrayLengths::default())).unwrap();
    let shared = [
        rust_layout!(Triangle {
            v0,
            material,
            v1,
            emitter,
            v2,
            planar_mirror,
            n,
            pad1
        }),
        rust_layout!(Sphere {
            center,
            radius,
            material,
            emitter,
            flip,
            pad0
        }),
        rust_layout!(Material {
            color,
            kind,
            emission,
            ior
        }),
        rust_layout!(Emitter {
            prim,
            area,
            cdf,
            pmf
        }),
        rust_layout!(BvhNode {
            min_x,
            max_x,
            min_y,
            max_y,
            min_z,
            max_z,
            child,
            count
        }),
        rust_layout!(Camera {
            eye,
            width,
            forward,
            height,
            right,
            pad0,
            up,
            pad1
        }),
        rust_layout!(Frame {
            camera,
            seed,
            first_sample,
            sample_count,
            num_emitters,
            tile_origin,
            tile_size,
            max_bounces,
            specular_scale,
            light_samples,
            grey_indirect,
            method,
            n_light_paths,
            slot,
            vertex_capacity,
            path_origin,
            path_count,
            importance_missing_cos,
            shadow_threshold,
            merge_vm,
            merge_vc,
            merge_normalization,
            film_row,
            film_rows,
            band_pixels,
            wave_origin,
            continue_at_vanishing_density,
            merge_rr_threshold,
            merge_rr_undivided,
            planar_mirror_count,
            camera_goes_on,
            merge_radius,
            merges_within_clearance,
            clearance_floor,
            merge_reach,
            sampler,
            run_offset,
            run_count,
            pad4,
            planar_mirrors
        }),
        rust_layout!(PlanarMirror {
            n,
            d,
            lo,
            tolerance,
            hi,
            material
        }),
        rust_layout!(GridParams {
            min,
            inv_cell,
            mask,
            count,
            radius2,
            pad
        }),
        rust_layout!(LightVertex {
            p,
            p_err,
            n,
            material,
            wo,
            length,
            throughput,
            next,
            d_vcm,
            d_vc,
            d_vm,
            path
        }),
        rust_layout!(PhotonRecord {
            n,
            length,
            throughput,
            w_light
        }),
        rust_layout!(PixelSums {
            sum,
            n,
            sum_sq,
            dropped,
            even_sum,
            even_n
        }),
        rust_layout!(PatchGrid { first, n, m, sides }),
        rust_layout!(Patch {
            albedo,
            prim,
            emission,
            cell,
            side,
            area,
            pad0,
            pad1
        }),
        rust_layout!(RadiosityParams {
            patch_count,
            rays_per_patch,
            first_ray,
            ray_count,
            seed,
            triangle_count,
            step_input,
            step_output,
            form_factor_scale,
            uniform_directions,
            indirect_with_direct,
            pad0
        }),
    ];
    for (name, size, fields) in shared {
        let (wsize, wfields) = wgsl_layout(&module, name);
        assert_eq!(fields, wfields, "{name}: fields and offsets (Rust vs WGSL)");
        assert_eq!(size, wsize, "{name}: size (Rust vs WGSL)");
    }
}

/// The test has power: a struct whose field order differs from its WGSL twin is caught.
#[test]
fn a_reordered_field_is_caught() {
    #[repr(C)]
    struct Emitter {
        area: f32,
        prim: u32,
        cdf: f32,
        pmf: f32,
    }
    let (module, _) = validate(&source(Residency::Storage, ArrayLengths::default())).unwrap();
    let (_, _, fields) = rust_layout!(Emitter {
        area,
        prim,
        cdf,
        pmf
    });
    let (_, wfields) = wgsl_layout(&module, "Emitter");
    assert_ne!(fields, wfields);
}

/// The value of the WGSL module-scope constant `name`, if it is a u32 or f32 literal.
fn wgsl_constant(module: &naga::Module, name: &str) -> Option<f64> {
    let constant = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?
        .1;
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::F32(v)) => Some(f64::from(v)),
        _ => None,
    }
}

/// (name, value) of Rust constants, each name written once, the value exact in f64.
macro_rules! rust_constants {
    ($($c:ident),* $(,)?) => {
        vec![$((stringify!($c), f64::from($c))),*]
    };
}

/// The constants that the WGSL declares again, with their Rust values (each exact in f64).
fn shared_constants() -> Vec<(&'static str, f64)> {
    use hexray::accel::hash_grid::QUERY_MARGIN;
    use hexray::cpu::path::{RR_MAX_SURVIVAL, RR_START_BOUNCE};
    use hexray::cpu::whitted::WHITTED_MAX_DEPTH;
    use hexray::gpu::bidirectional::SCAN_BLOCK;
    use hexray::layout::{
        EMPTY_SLOT, KIND_DIFFUSE, KIND_EMITTER, KIND_GLASS, KIND_MIRROR, NOT_AN_EMITTER,
        PRIM_PADDING, PRIM_SPHERE_BIT,
    };
    use hexray::math::sampling::{DIM_CAMERA, DIM_EMISSION, DIM_EMISSION_DIR};
    use hexray::transport::clearance::{COPLANAR_COS, COPLANAR_OFFSET};
    use hexray::transport::merging::FOOTPRINT_FLOOR;
    use hexray::transport::patches::{DIM_FORM_FACTOR, NO_PATCHES};
    use hexray::transport::planar_mirror::{BOUNDS_SLACK, MAX_PLANAR_MIRRORS, NO_PLANAR_MIRROR};
    use hexray::transport::splat::FRACTION_BITS;
    use hexray::transport::subpath::{LIGHT_SUBPATH_RR_START_BOUNCE, NO_VERTEX};
    rust_constants!(
        RR_START_BOUNCE,
        RR_MAX_SURVIVAL,
        LIGHT_SUBPATH_RR_START_BOUNCE,
        KIND_DIFFUSE,
        KIND_MIRROR,
        KIND_GLASS,
        KIND_EMITTER,
        NOT_AN_EMITTER,
        PRIM_SPHERE_BIT,
        PRIM_PADDING,
        MAX_PLANAR_MIRRORS,
        NO_PLANAR_MIRROR,
        BOUNDS_SLACK,
        EMPTY_SLOT,
        NO_VERTEX,
        DIM_CAMERA,
        DIM_EMISSION,
        DIM_EMISSION_DIR,
        FRACTION_BITS,
        SCAN_BLOCK,
        COPLANAR_COS,
        COPLANAR_OFFSET,
        FOOTPRINT_FLOOR,
        QUERY_MARGIN,
        WHITTED_MAX_DEPTH,
        DIM_FORM_FACTOR,
        NO_PATCHES,
    )
}

/// Every shared constant whose WGSL declaration is missing or differs from Rust's, as a line.
fn constant_mismatches(wgsl: &str) -> Vec<String> {
    let (module, _) = validate(wgsl).unwrap();
    shared_constants()
        .into_iter()
        .filter_map(|(name, rust)| match wgsl_constant(&module, name) {
            Some(w) if w == rust => None,
            w => Some(format!("{name}: Rust {rust}, WGSL {w:?}")),
        })
        .collect()
}

/// The constants that steer both backends' estimators (roulette, material kinds, random-stream
/// blocks, the splats' fixed point) are written in Rust and again in WGSL; naga's reflection of
/// the WGSL must give Rust's value for each.
#[test]
fn shared_constants_match_their_wgsl_declarations() {
    let mismatches = constant_mismatches(&source(Residency::Storage, ArrayLengths::default()));
    assert!(mismatches.is_empty(), "{mismatches:#?}");
}

/// The test has power: a shader whose roulette starts at another bounce than Rust's is caught.
#[test]
fn a_drifted_constant_is_caught() {
    let wgsl = source(Residency::Storage, ArrayLengths::default());
    let start = hexray::transport::subpath::LIGHT_SUBPATH_RR_START_BOUNCE;
    let declared = format!("const LIGHT_SUBPATH_RR_START_BOUNCE: u32 = {start}u;");
    assert!(wgsl.contains(&declared));
    let drifted = wgsl.replace(
        &declared,
        &format!("const LIGHT_SUBPATH_RR_START_BOUNCE: u32 = {}u;", start + 1),
    );
    let mismatches = constant_mismatches(&drifted);
    assert_eq!(mismatches.len(), 1, "{mismatches:#?}");
    assert!(mismatches[0].starts_with("LIGHT_SUBPATH_RR_START_BOUNCE"));
}
