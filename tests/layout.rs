//! The scene layout is defined once in Rust (`#[repr(C)]` + bytemuck) and declared again in
//! WGSL; this test compares every shared struct's size, field names and field offsets with
//! naga's reflection of the WGSL declarations, so the two cannot drift apart.

use hexray::camera::Camera;
use hexray::flat::{BvhNode, Emitter, Material, Sphere, Triangle};
use hexray::gpu::render::{Frame, PixelSums};
use hexray::gpu::shader::{source, validate, ArrayLengths, Residency};
use hexray::hash_grid::GridParams;
use hexray::subpath::LightVertex;
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
            pad0,
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
            pad
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
        rust_layout!(PixelSums {
            sum,
            n,
            sum_sq,
            dropped
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
