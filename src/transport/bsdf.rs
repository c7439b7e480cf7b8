//! The three scattering models: two-sided Lambert, perfect mirror, smooth dielectric.
//!
//! Directions point away from the surface: `wo` toward where the light goes (the previous
//! vertex), `wi` toward where it comes from. A sample's `weight` is f · |cos θi| / pdf, the factor
//! by which the path throughput changes.

use crate::layout::{Material, KIND_DIFFUSE, KIND_EMITTER, KIND_GLASS, KIND_MIRROR};
use crate::math::sampling::{orthonormal_basis, sample_cosine_hemisphere};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Whether a material scatters diffusely (Lambert): diffuse surfaces, and emitters that also
/// reflect. Only such vertices can be connected.
#[inline]
pub fn is_diffuse(material: &Material) -> bool {
    material.kind == KIND_DIFFUSE
        || (material.kind == KIND_EMITTER && Vec3::from(material.color).max_element() > 0.0)
}

/// Unpolarised Fresnel reflectance of a smooth dielectric boundary (exact, not Schlick's
/// approximation): the mean of the s- and p-polarised reflectances (pbrt-v4 eq. 9.6), with
/// `cos_i` measured on the side the light arrives from relative to the normal `eta` is defined
/// for (`eta` = inside over outside). Returns 1 under total internal reflection.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        // Arriving from inside: swap the media.
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// Mirror reflection of `wo` about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Snell refraction of `wo` through a boundary with normal `n` and relative index `eta`
/// (inside over outside). Returns the transmitted direction and the relative index `etap` of the
/// side it enters over the side it leaves, or None under total internal reflection.
#[inline]
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = wo.dot(n);
    let (mut n, mut eta) = (n, eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let wt = -wo / eta + (cos_i / eta - cos_t) * n;
    Some((wt.normalize(), eta))
}

/// Which quantity a path carries (pbrt-v4's `TransportMode`): camera subpaths carry radiance
/// toward the camera, light subpaths carry importance toward the lights (their throughput is
/// flux). The BSDFs here are symmetric except refraction, whose radiance scales by 1/η² across
/// the boundary while flux does not (Veach's thesis, section 5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    Radiance,
    Importance,
}

/// The two-sided Lambertian BSDF evaluated for a pair of directions, as a connection needs it.
#[derive(Clone, Copy, Debug)]
pub struct DiffuseEval {
    /// f = albedo / π where `wo` and `wi` lie on one side of the surface, else 0.
    pub f: Vec3,
    /// |cos θi|: the cosine at the surface toward `wi` (0 where f is).
    pub cos_i: f32,
    /// Solid-angle density with which sampling from `wo` picks `wi`: cos θi / π.
    pub pdf: f32,
    /// The reverse: the density of `wo` when sampling from `wi`, cos θo / π.
    pub pdf_rev: f32,
}

/// Evaluates the Lambertian BSDF of albedo `albedo` at a surface whose unit normal `n_facing`
/// points to the side of `wo`.
#[inline]
pub fn eval_diffuse(albedo: Vec3, n_facing: Vec3, wo: Vec3, wi: Vec3) -> DiffuseEval {
    let cos_i = n_facing.dot(wi);
    if cos_i <= 0.0 {
        return DiffuseEval {
            f: Vec3::ZERO,
            cos_i: 0.0,
            pdf: 0.0,
            pdf_rev: 0.0,
        };
    }
    DiffuseEval {
        f: albedo * FRAC_1_PI,
        cos_i,
        pdf: cos_i * FRAC_1_PI,
        pdf_rev: n_facing.dot(wo).max(0.0) * FRAC_1_PI,
    }
}

/// A sampled direction and what it does to the path.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f · |cos θi| / pdf.
    pub weight: Vec3,
    /// Solid-angle pdf of `wi`; 0 for a specular (Dirac) lobe, which light sampling cannot hit.
    pub pdf: f32,
    /// The square of the relative index crossed (1 unless refracted), for Russian roulette.
    pub eta2: f32,
}

/// Samples the BSDF of material `m` at a surface with unit geometric normal `n`, for outgoing
/// direction `wo`, from two uniform numbers for the direction and one for the lobe. Diffuse
/// surfaces are two-sided: they scatter into the hemisphere `wo` lies in.
#[inline]
pub fn sample_bsdf(
    m: &Material,
    n: Vec3,
    wo: Vec3,
    u: [f32; 4],
    transport: Transport,
) -> BsdfSample {
    let color = Vec3::from(m.color);
    match m.kind {
        KIND_MIRROR => BsdfSample {
            wi: reflect(wo, n),
            weight: color,
            pdf: 0.0,
            eta2: 1.0,
        },
        KIND_GLASS => {
            // Choose reflection with probability F, refraction with 1 - F: the weight of each
            // lobe is then exactly its Fresnel factor over its probability, 1.
            let f = fresnel_dielectric(wo.dot(n), m.ior);
            if u[2] < f {
                BsdfSample {
                    wi: reflect(wo, n),
                    weight: Vec3::ONE,
                    pdf: 0.0,
                    eta2: 1.0,
                }
            } else {
                // F < 1, so refraction exists. Radiance is not conserved across the boundary:
                // L scales by 1 / etap² when carried from the entered side back to the left
                // side (pbrt-v4 eq. 9.17, `TransportMode::Radiance`); flux (importance
                // transport, light subpaths) is.
                let (wi, etap) = refract(wo, n, m.ior).unwrap_or((reflect(wo, n), 1.0));
                let eta2 = etap * etap;
                BsdfSample {
                    wi,
                    weight: match transport {
                        Transport::Radiance => color / eta2,
                        Transport::Importance => color,
                    },
                    pdf: 0.0,
                    eta2,
                }
            }
        }
        // Diffuse, and emitters that also reflect: Lambert, f = albedo / pi, sampled with
        // the cosine-weighted pdf cos θ / pi, so the weight is the albedo.
        _ => {
            let nf = if wo.dot(n) < 0.0 { -n } else { n };
            let local = sample_cosine_hemisphere(u[0], u[1]);
            let (t, b) = orthonormal_basis(nf);
            // Unit to rounding: an orthonormal basis times a unit vector.
            let wi = local.x * t + local.y * b + local.z * nf;
            BsdfSample {
                wi,
                weight: color,
                pdf: local.z * FRAC_1_PI,
                eta2: 1.0,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{KIND_DIFFUSE, KIND_GLASS};

    #[test]
    fn fresnel_at_normal_incidence_is_4_percent_for_glass() {
        // ((1.5 - 1) / (1.5 + 1))² = 0.04 exactly.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
    }

    #[test]
    fn beyond_the_critical_angle_glass_reflects_everything() {
        // From inside glass of index 1.5 the critical angle is asin(1/1.5) = 41.8 degrees.
        let cos_60 = 0.5f32;
        assert_eq!(fresnel_dielectric(-cos_60, 1.5), 1.0);
        assert!(refract(Vec3::new(0.866, 0.0, -0.5), Vec3::Z, 1.5).is_none());
    }

    #[test]
    fn fresnel_matches_the_polarised_formulas_at_45_degrees() {
        // Independent evaluation in f64 of Rs and Rp from Snell's law.
        let (n1, n2) = (1.0f64, 1.5f64);
        let ti = std::f64::consts::FRAC_PI_4;
        let tt = (n1 / n2 * ti.sin()).asin();
        let rs = ((n1 * ti.cos() - n2 * tt.cos()) / (n1 * ti.cos() + n2 * tt.cos())).powi(2);
        let rp = ((n1 * tt.cos() - n2 * ti.cos()) / (n1 * tt.cos() + n2 * ti.cos())).powi(2);
        let got = fresnel_dielectric(ti.cos() as f32, 1.5) as f64;
        assert!(
            (got - 0.5 * (rs + rp)).abs() < 1e-6,
            "{got} vs {}",
            0.5 * (rs + rp)
        );
    }

    #[test]
    fn mirror_weight_is_the_reflectance() {
        let m = Material {
            color: [0.9, 0.5, 0.25],
            kind: KIND_MIRROR,
            ..Default::default()
        };
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = sample_bsdf(&m, Vec3::Z, wo, [0.3, 0.7, 0.5, 0.0], Transport::Radiance);
        assert_eq!(s.weight, Vec3::new(0.9, 0.5, 0.25));
        assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
    }

    #[test]
    fn refraction_obeys_snell_and_scales_radiance_by_eta_squared() {
        let m = Material {
            color: [1.0; 3],
            kind: KIND_GLASS,
            ior: 1.5,
            ..Default::default()
        };
        let wo = Vec3::new(0.6, 0.0, 0.8);
        // u[2] = 0.999 > F: refract into the glass.
        let s = sample_bsdf(&m, Vec3::Z, wo, [0.0, 0.0, 0.999, 0.0], Transport::Radiance);
        let sin_t = (s.wi.x * s.wi.x + s.wi.y * s.wi.y).sqrt();
        assert!((sin_t * 1.5 - 0.6).abs() < 1e-6 && s.wi.z < 0.0);
        assert!((s.weight.x - 1.0 / 2.25).abs() < 1e-6 && (s.eta2 - 2.25).abs() < 1e-6);
    }

    /// Averaging the weight of N cosine samples gives the albedo exactly (the estimator of the
    /// directional albedo has zero variance for Lambert with cosine sampling); the directions
    /// stay in the hemisphere of wo on both sides of the surface.
    #[test]
    fn diffuse_sample_weight_averages_to_the_albedo() {
        let m = Material {
            color: [0.8, 0.5, 0.2],
            kind: KIND_DIFFUSE,
            ..Default::default()
        };
        for wo in [Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.0, 0.6, -0.8)] {
            let mut acc = glam::DVec3::ZERO;
            let n = 10_000;
            for i in 0..n {
                let u = crate::math::sampling::Sampler::new(1, i, 0).draw4(0);
                let s = sample_bsdf(&m, Vec3::Z, wo, u, Transport::Radiance);
                assert!(s.wi.z * wo.z > 0.0 && s.pdf > 0.0);
                acc += s.weight.as_dvec3();
            }
            let mean = acc / n as f64;
            assert!((mean - Vec3::new(0.8, 0.5, 0.2).as_dvec3()).length() < 1e-12);
        }
    }
}
