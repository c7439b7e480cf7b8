//! The builder of the layout: a validated scene file flattened into the plain-data arrays both
//! backends read ([`FlatScene`]): materials in name order, triangles (the listed triangles, then
//! the meshes', then the boxes' expanded), spheres, the emitter table, the BVH over all
//! primitives with the CPU's forms of it (triangle packs, the eight-wide tree), and the planar
//! mirrors.

use crate::accel::bvh::{self, Traversal};
use crate::layout::{
    sphere_area, triangle_area, BvhNode, Emitter, FlatScene, Material, Sphere, Triangle, WideNode,
    KIND_DIFFUSE, KIND_EMITTER, KIND_GLASS, KIND_MIRROR, PRIM_SPHERE_BIT,
};
use crate::scene::{MaterialDesc, Scene};
use crate::transport::planar_mirror;

fn f3(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

impl FlatScene {
    /// Flattens a validated scene: materials in name order, triangles (the listed triangles, then
    /// the meshes' in `meshes` order, then the boxes' expanded), spheres, the emitter table, and
    /// the BVH over all primitives, built for `traversal` (either backend renders any tree
    /// right, another's only slower).
    pub fn build(scene: &Scene, traversal: Traversal) -> FlatScene {
        let desc = &scene.desc;
        let names: Vec<&String> = desc.materials.keys().collect();
        let material_id = |name: &str| names.iter().position(|n| *n == name).unwrap() as u32;
        let materials: Vec<Material> = desc
            .materials
            .values()
            .map(|m| match m {
                MaterialDesc::Diffuse { albedo } => Material {
                    color: f3(*albedo),
                    kind: KIND_DIFFUSE,
                    ..Default::default()
                },
                MaterialDesc::Mirror { reflectance } => Material {
                    color: f3(*reflectance),
                    kind: KIND_MIRROR,
                    ..Default::default()
                },
                MaterialDesc::Glass { ior, tint } => Material {
                    color: f3(*tint),
                    kind: KIND_GLASS,
                    ior: *ior as f32,
                    ..Default::default()
                },
                MaterialDesc::Emitter {
                    radiance, albedo, ..
                } => Material {
                    color: f3(*albedo),
                    kind: KIND_EMITTER,
                    emission: f3(*radiance),
                    ior: 0.0,
                },
            })
            .collect();

        let mut triangles: Vec<Triangle> = Vec::with_capacity(scene.triangle_count());
        let push = |triangles: &mut Vec<Triangle>, v: [[f64; 3]; 3], material: &str| {
            triangles.push(Triangle::new(
                f3(v[0]),
                f3(v[1]),
                f3(v[2]),
                material_id(material),
            ))
        };
        for t in &desc.triangles {
            push(&mut triangles, t.v, &t.material);
        }
        // Meshes after the inline triangles, in file order: a mesh and the same triangles
        // written inline after the others give the same list, so the same render.
        for m in &scene.meshes {
            let id = material_id(&m.material);
            triangles.extend(
                m.triangles
                    .iter()
                    .map(|v| Triangle::new(v[0], v[1], v[2], id)),
            );
        }
        for b in &desc.boxes {
            for v in b.triangles() {
                push(&mut triangles, v, &b.material);
            }
        }
        let spheres: Vec<Sphere> = desc
            .spheres
            .iter()
            .map(|s| Sphere {
                center: f3(s.center),
                radius: s.radius as f32,
                material: material_id(&s.material),
                flip: u32::from(s.flip_normals),
                ..Default::default()
            })
            .collect();

        let mut spheres = spheres;
        let emitters = build_emitter_table(&mut triangles, &mut spheres, &materials);
        let started = std::time::Instant::now();
        let (nodes, prims, wide) = bvh::build_trees(&triangles, &spheres, traversal);
        let bvh_seconds = started.elapsed().as_secs_f64();
        let planar_mirrors = planar_mirror::find(&mut triangles, &materials);
        FlatScene {
            bvh_seconds,
            planar_mirrors,
            materials,
            emitters,
            ..FlatScene::from_tree(triangles, spheres, nodes, prims, wide)
        }
    }

    /// A scene of these primitives and these trees (`bvh::build_trees`'), with the triangle
    /// packs the CPU derives from them and no materials or emitters: for tests and tools that
    /// build a tree themselves.
    pub fn from_tree(
        triangles: Vec<Triangle>,
        spheres: Vec<Sphere>,
        nodes: Vec<BvhNode>,
        prims: Vec<u32>,
        wide: Vec<WideNode>,
    ) -> FlatScene {
        FlatScene {
            packs: bvh::triangle_packs(&triangles, &prims),
            wide,
            triangles,
            spheres,
            nodes,
            prims,
            ..Default::default()
        }
    }
}

/// The emitter table: every triangle, then every sphere, whose material emits, chosen with
/// probability proportional to its power (area x mean of the RGB radiance; the pi of Lambertian
/// emission is common to all and cancels). Sets each emitting primitive's `emitter` row.
fn build_emitter_table(
    triangles: &mut [Triangle],
    spheres: &mut [Sphere],
    materials: &[Material],
) -> Vec<Emitter> {
    let mut rows = Vec::new();
    let mut powers = Vec::new();
    let mean_emission = |material: u32| {
        let m = &materials[material as usize];
        let mean_le = (m.emission[0] + m.emission[1] + m.emission[2]) as f64 / 3.0;
        (m.kind == KIND_EMITTER && mean_le > 0.0).then_some(mean_le)
    };
    let mut push = |prim: u32, area: f32, mean_le: f64| {
        rows.push(Emitter {
            prim,
            area,
            cdf: 0.0,
            pmf: 0.0,
        });
        powers.push(area as f64 * mean_le);
    };
    for (i, t) in triangles.iter().enumerate() {
        if let Some(mean_le) = mean_emission(t.material) {
            push(i as u32, triangle_area(t), mean_le);
        }
    }
    for (i, s) in spheres.iter().enumerate() {
        if let Some(mean_le) = mean_emission(s.material) {
            push(i as u32 | PRIM_SPHERE_BIT, sphere_area(s), mean_le);
        }
    }
    let total: f64 = powers.iter().sum();
    let mut acc = 0.0f64;
    for (row, p) in rows.iter_mut().zip(&powers) {
        acc += p;
        row.pmf = (p / total) as f32;
        row.cdf = (acc / total) as f32;
    }
    if let Some(last) = rows.last_mut() {
        last.cdf = 1.0;
    }
    for (k, row) in rows.iter().enumerate() {
        if row.prim & PRIM_SPHERE_BIT != 0 {
            spheres[(row.prim & !PRIM_SPHERE_BIT) as usize].emitter = k as u32;
        } else {
            triangles[row.prim as usize].emitter = k as u32;
        }
    }
    rows
}
