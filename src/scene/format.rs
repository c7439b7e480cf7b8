//! The scene file format: the JSON of `scenes/*.json`, as serde structs.
//!
//! Unknown fields are rejected everywhere, so a misspelt key is an error with its location
//! rather than a silently ignored setting. Numbers are read as f64 and checked to fit f32
//! (the renderer's precision) by [`super::validate`].

use serde::Deserialize;
use std::collections::BTreeMap;

/// A whole scene: one pinhole camera, named materials, and the geometry that uses them.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct SceneDesc {
    /// The scene's name, for logs and output metadata.
    #[serde(default)]
    pub name: String,
    /// Where the scene comes from (free text, not used by the renderer).
    #[serde(default)]
    pub seed: Option<String>,
    /// Conventions the scene assumes (free text, not used by the renderer).
    #[serde(default)]
    pub notes: Vec<String>,
    /// The pinhole camera.
    pub camera: CameraDesc,
    /// Materials by name; geometry refers to them by these names.
    pub materials: BTreeMap<String, MaterialDesc>,
    /// Triangles, each with its own three vertices.
    #[serde(default)]
    pub triangles: Vec<TriangleDesc>,
    /// Spheres.
    #[serde(default)]
    pub spheres: Vec<SphereDesc>,
    /// Axis-aligned boxes, each expanded to 12 outward-facing triangles.
    #[serde(default)]
    pub boxes: Vec<BoxDesc>,
    /// Triangle meshes read from PLY or OBJ files; their triangles join the scene's triangle
    /// list after `triangles` and before the boxes' (see [`MeshDesc`]).
    #[serde(default)]
    pub meshes: Vec<MeshDesc>,
}

/// A pinhole camera; images are as wide as `--width` and as tall as `--height`, with square
/// pixels, so the horizontal field of view follows from the aspect ratio.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct CameraDesc {
    /// The centre of projection.
    pub eye: [f64; 3],
    /// A point the camera looks at (on the optical axis).
    pub look_at: [f64; 3],
    /// The world direction that appears upward in the image; must not be parallel to the view.
    pub up: [f64; 3],
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f64,
    /// A note for people (e.g. which world direction is image left); not used by the renderer.
    #[serde(default)]
    pub note: Option<String>,
}

/// The four material kinds. `type` selects the kind; each kind takes only its own fields.
///
/// Read as a [`RawMaterial`] (one object with every material field), then checked to hold only
/// its kind's fields: the fields are read in place, so an error in one points at that field,
/// which serde's buffered internally tagged enums cannot do.
#[derive(Debug, Clone)]
pub enum MaterialDesc {
    /// Two-sided Lambertian reflector.
    Diffuse {
        /// Linear RGB reflectance (the hemispherical albedo), each channel in [0, 1].
        albedo: [f64; 3],
    },
    /// Perfect specular reflector.
    Mirror {
        /// Linear RGB reflectance, each channel in [0, 1].
        reflectance: [f64; 3],
    },
    /// Smooth dielectric: exact unpolarised Fresnel, total internal reflection.
    Glass {
        /// Index of refraction inside (outside is 1.0); must be > 0.
        ior: f64,
        /// Multiplies the light at each refraction, each channel in [0, 1]; default white.
        tint: [f64; 3],
    },
    /// One-sided area light: emits on the side of (v1 - v0) x (v2 - v0), black behind.
    Emitter {
        /// Emitted linear RGB radiance, each channel >= 0.
        radiance: [f64; 3],
        /// Must be true when given: two-sided emitters are not modelled.
        one_sided: bool,
        /// Optional Lambertian reflectance of the emitting surface (default black), each
        /// channel in [0, 1]; the furnace tests use emitters that also reflect.
        albedo: [f64; 3],
    },
}

fn white() -> [f64; 3] {
    [1.0; 3]
}
fn yes() -> bool {
    true
}

/// One triangle. Its winding fixes the emitting side of an emitter.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct TriangleDesc {
    /// The three vertices.
    pub v: [[f64; 3]; 3],
    /// The name of a material in `materials`.
    pub material: String,
    /// A human label (e.g. "wall AB"); not used by the renderer.
    #[serde(default)]
    pub part: Option<String>,
}

/// One sphere.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct SphereDesc {
    /// Centre.
    pub center: [f64; 3],
    /// Radius, > 0.
    pub radius: f64,
    /// The name of a material in `materials`; an emitter makes the sphere an area light.
    pub material: String,
    /// Normals point inward (Mitsuba's `flip_normals`): an emitting sphere then lights its
    /// inside, and a glass sphere becomes a bubble of air in glass.
    #[serde(default)]
    pub flip_normals: bool,
}

/// An axis-aligned box, expanded to 12 triangles whose normals face outward.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct BoxDesc {
    /// The minimum corner.
    pub min: [f64; 3],
    /// The maximum corner; strictly greater than `min` on every axis.
    pub max: [f64; 3],
    /// The name of a material in `materials`.
    pub material: String,
}

/// A triangle mesh from a file, placed in the scene by a scale, a rotation and a translation.
///
/// Each vertex `v` of the file becomes `translate + R (scale * v)`, computed in f64 from the
/// file's values (a PLY's float vertices are exact in f64; an OBJ's decimals are read as f64)
/// and rounded to f32 once, as the numbers of inline `triangles` are. Without `rotate` the
/// arithmetic is exactly `(v * s) + t` per coordinate in f64 (two roundings, in that order), so
/// a mesh renders bit for bit like the same triangles written inline with those f64 values.
/// With `rotate`, `R (s v)` is the sum `R[i][0] (s v)_x + R[i][1] (s v)_y + R[i][2] (s v)_z`
/// from left to right, with R Rodrigues' matrix of the unit axis; for a multiple of 90 degrees
/// cos and sin are taken exactly (0, 1 or -1), so quarter turns move vertices exactly.
///
/// Faces with more than three vertices are fanned, (v0, v_i, v_i+1) for i = 1 .. n - 2, as pbrt
/// does; the winding of the file is kept, and the normal is the geometric one,
/// (v1 - v0) x (v2 - v0) (flat shading; an emitter emits on that side). A triangle that has zero
/// area once rounded to f32 is dropped and counted (`render` and `info` report the count and
/// the first such face); every other defect of the file is an error that names it.
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct MeshDesc {
    /// The mesh file, relative to the folder of the scene file: `.ply` (ASCII, binary little or
    /// big endian; float or double vertices; faces as a list of any integer type) or `.obj`
    /// (`v` and `f` lines; `f` accepts `i`, `i/t`, `i//n`, `i/t/n` and negative, relative,
    /// indices; everything else is ignored).
    pub file: String,
    /// The name of a material in `materials`, for every triangle of the mesh.
    pub material: String,
    /// A uniform scale factor, or one per axis [sx, sy, sz]; each nonzero. Default 1.
    #[serde(default)]
    pub scale: Option<Scale>,
    /// A rotation about an axis through the origin, applied after the scale.
    #[serde(default)]
    pub rotate: Option<RotateDesc>,
    /// A translation [tx, ty, tz], applied last. Default [0, 0, 0].
    #[serde(default)]
    pub translate: Option<[f64; 3]>,
}

/// A mesh's scale: one number for all axes, or one per axis.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f64),
    PerAxis([f64; 3]),
}

impl Scale {
    /// The factor per axis.
    pub fn per_axis(self) -> [f64; 3] {
        match self {
            Scale::Uniform(s) => [s; 3],
            Scale::PerAxis(v) => v,
        }
    }
}

/// A rotation by `degrees` about `axis`, counter-clockwise seen from the axis's tip (the
/// right-hand rule).
#[derive(Debug, Clone, Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
pub struct RotateDesc {
    /// The axis; any nonzero length (it is normalised in f64).
    pub axis: [f64; 3],
    /// The angle in degrees.
    pub degrees: f64,
}

impl MeshDesc {
    /// The f64 transform of this mesh: `translate + R (scale * v)`. The arithmetic is documented
    /// on [`MeshDesc`].
    pub fn transform(&self) -> MeshTransform {
        let scale = self.scale.map_or([1.0; 3], Scale::per_axis);
        let rotation = self
            .rotate
            .as_ref()
            .map(|r| rotation_matrix(r.axis, r.degrees));
        MeshTransform {
            scale,
            rotation,
            translate: self.translate.unwrap_or([0.0; 3]),
        }
    }
}

/// A mesh's placement in f64: scale, then rotation (when given), then translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshTransform {
    pub scale: [f64; 3],
    pub rotation: Option<[[f64; 3]; 3]>,
    pub translate: [f64; 3],
}

impl MeshTransform {
    /// Where vertex `v` goes, in f64.
    #[inline]
    pub fn apply(&self, v: [f64; 3]) -> [f64; 3] {
        let s = [
            v[0] * self.scale[0],
            v[1] * self.scale[1],
            v[2] * self.scale[2],
        ];
        let r = match &self.rotation {
            None => s,
            Some(m) => [0, 1, 2].map(|i| m[i][0] * s[0] + m[i][1] * s[1] + m[i][2] * s[2]),
        };
        [
            r[0] + self.translate[0],
            r[1] + self.translate[1],
            r[2] + self.translate[2],
        ]
    }
}

/// Cosine and sine of an angle in degrees, exact (0, 1 or -1) at multiples of 90.
fn cos_sin_degrees(degrees: f64) -> (f64, f64) {
    let quarter = degrees / 90.0;
    if quarter == quarter.round() && quarter.abs() < 1e15 {
        match (quarter as i64).rem_euclid(4) {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 0.0),
            _ => (0.0, -1.0),
        }
    } else {
        let r = degrees.to_radians();
        (r.cos(), r.sin())
    }
}

/// Rodrigues' rotation matrix (row-major) for `degrees` about `axis` (normalised here; the
/// caller has checked it is nonzero and finite).
pub fn rotation_matrix(axis: [f64; 3], degrees: f64) -> [[f64; 3]; 3] {
    let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / len);
    let (c, s) = cos_sin_degrees(degrees);
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

impl BoxDesc {
    /// The 12 triangles of the box, wound so that (v1 - v0) x (v2 - v0) points out of the box.
    pub fn triangles(&self) -> [[[f64; 3]; 3]; 12] {
        let (a, b) = (self.min, self.max);
        // Corner k has x from bit 0, y from bit 1, z from bit 2.
        let c = |k: usize| {
            [
                if k & 1 == 0 { a[0] } else { b[0] },
                if k & 2 == 0 { a[1] } else { b[1] },
                if k & 4 == 0 { a[2] } else { b[2] },
            ]
        };
        // Each face as a quad (p0, p1, p2, p3) counter-clockwise seen from outside.
        const FACES: [[usize; 4]; 6] = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        let mut out = [[[0.0; 3]; 3]; 12];
        for (f, q) in FACES.iter().enumerate() {
            out[2 * f] = [c(q[0]), c(q[1]), c(q[2])];
            out[2 * f + 1] = [c(q[0]), c(q[2]), c(q[3])];
        }
        out
    }
}

/// Every field any material takes; [`MaterialDesc`]'s `Deserialize` reads this, then checks
/// that only the kind's own fields were given.
#[derive(Deserialize)]
#[serde(remote = "Self", deny_unknown_fields)]
struct RawMaterial {
    #[serde(rename = "type")]
    kind: MaterialKind,
    albedo: Option<[f64; 3]>,
    reflectance: Option<[f64; 3]>,
    ior: Option<f64>,
    tint: Option<[f64; 3]>,
    radiance: Option<[f64; 3]>,
    one_sided: Option<bool>,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "snake_case")]
enum MaterialKind {
    Diffuse,
    Mirror,
    Glass,
    Emitter,
}

impl RawMaterial {
    /// The material, or the message for the first field its kind does not take (worded as
    /// serde's "unknown field" so that the loader points at the field) or lacks.
    fn into_desc(self) -> Result<MaterialDesc, String> {
        use MaterialKind::*;
        let (kind, own): (&str, &[&str]) = match self.kind {
            Diffuse => ("diffuse", &["albedo"]),
            Mirror => ("mirror", &["reflectance"]),
            Glass => ("glass", &["ior", "tint"]),
            Emitter => ("emitter", &["radiance", "one_sided", "albedo"]),
        };
        let given = [
            ("albedo", self.albedo.is_some()),
            ("reflectance", self.reflectance.is_some()),
            ("ior", self.ior.is_some()),
            ("tint", self.tint.is_some()),
            ("radiance", self.radiance.is_some()),
            ("one_sided", self.one_sided.is_some()),
        ];
        if let Some((field, _)) = given.iter().find(|(f, g)| *g && !own.contains(f)) {
            let expected: Vec<String> = std::iter::once("type")
                .chain(own.iter().copied())
                .map(|f| format!("`{f}`"))
                .collect();
            return Err(format!(
                "unknown field `{field}`, a {kind} material takes {}",
                expected.join(", ")
            ));
        }
        let missing = |f: &str| format!("missing field `{f}` (a {kind} material needs it)");
        Ok(match self.kind {
            Diffuse => MaterialDesc::Diffuse {
                albedo: self.albedo.ok_or_else(|| missing("albedo"))?,
            },
            Mirror => MaterialDesc::Mirror {
                reflectance: self.reflectance.ok_or_else(|| missing("reflectance"))?,
            },
            Glass => MaterialDesc::Glass {
                ior: self.ior.ok_or_else(|| missing("ior"))?,
                tint: self.tint.unwrap_or_else(white),
            },
            Emitter => MaterialDesc::Emitter {
                radiance: self.radiance.ok_or_else(|| missing("radiance"))?,
                one_sided: self.one_sided.unwrap_or_else(yes),
                albedo: self.albedo.unwrap_or_default(),
            },
        })
    }
}

impl<'de> Deserialize<'de> for MaterialDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let raw: RawMaterial = RawMaterial::deserialize(ObjectOnly(d))?;
        raw.into_desc().map_err(serde::de::Error::custom)
    }
}

/// `Deserialize` for the scene's structs, from JSON objects only. serde's derive also accepts a
/// struct written as an array of its fields in order (`"camera": [[0, 0, 0], ...]`), which no
/// one means to write; each struct derives with `remote = "Self"` (an inherent `deserialize`)
/// and is read here through [`ObjectOnly`], which asks for a map.
macro_rules! objects_only {
    ($($t:ty),*) => {$(
        impl<'de> Deserialize<'de> for $t {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                <$t>::deserialize(ObjectOnly(d))
            }
        }
    )*};
}
objects_only!(
    SceneDesc,
    CameraDesc,
    TriangleDesc,
    SphereDesc,
    BoxDesc,
    MeshDesc,
    RotateDesc
);

/// A deserializer that reads a struct as a map (never as a sequence) and passes everything else on.
struct ObjectOnly<D>(D);

impl<'de, D: serde::Deserializer<'de>> serde::Deserializer<'de> for ObjectOnly<D> {
    type Error = D::Error;

    fn deserialize_any<V: serde::de::Visitor<'de>>(self, v: V) -> Result<V::Value, D::Error> {
        self.0.deserialize_any(v)
    }

    fn deserialize_struct<V: serde::de::Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, D::Error> {
        self.0.deserialize_map(v)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_triangles_face_outward() {
        let bx = BoxDesc {
            min: [1.0, 2.0, 3.0],
            max: [2.0, 4.0, 7.0],
            material: "m".into(),
        };
        let centre = [1.5, 3.0, 5.0];
        for t in bx.triangles() {
            let e1: Vec<f64> = (0..3).map(|i| t[1][i] - t[0][i]).collect();
            let e2: Vec<f64> = (0..3).map(|i| t[2][i] - t[0][i]).collect();
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let out: f64 = (0..3).map(|i| n[i] * (t[0][i] - centre[i])).sum();
            assert!(out > 0.0, "triangle {t:?} faces inward");
        }
    }
}
