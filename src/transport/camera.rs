//! The pinhole camera: pixel coordinates to primary rays.

use crate::math::geometry::Ray;
use crate::scene::CameraDesc;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};

/// A pinhole camera in the layout both backends share (`Camera` in `shaders/scene.wgsl`).
/// `right` and `up` are scaled so that the image spans [-1, 1] along each of them at unit
/// distance along `forward`. Four vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Camera {
    pub eye: [f32; 3],
    pub width: u32,
    pub forward: [f32; 3],
    pub height: u32,
    /// Image right at unit distance, times tan(vfov / 2) x aspect.
    pub right: [f32; 3],
    pub pad0: u32,
    /// Image up at unit distance, times tan(vfov / 2).
    pub up: [f32; 3],
    pub pad1: u32,
}

impl Camera {
    /// A camera for an image of `width` x `height` square pixels. The basis is computed in f64
    /// and rounded once.
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let eye = DVec3::from(desc.eye);
        let forward = (DVec3::from(desc.look_at) - eye).normalize();
        let right = forward.cross(DVec3::from(desc.up)).normalize();
        let up = right.cross(forward);
        let tan_half = (desc.vfov_deg.to_radians() * 0.5).tan();
        let aspect = width as f64 / height as f64;
        Camera {
            eye: eye.as_vec3().into(),
            width,
            forward: forward.as_vec3().into(),
            height,
            right: (right * tan_half * aspect).as_vec3().into(),
            pad0: 0,
            up: (up * tan_half).as_vec3().into(),
            pad1: 0,
        }
    }

    /// The ray through image position (x + jx, y + jy), pixel (0, 0) at the top left; the jitter
    /// (jx, jy) in [0, 1)^2 is uniform over the pixel, which is the box filter.
    #[inline]
    pub fn ray(&self, x: u32, y: u32, jx: f32, jy: f32) -> Ray {
        let sx = 2.0 * ((x as f32 + jx) / self.width as f32) - 1.0;
        let sy = 1.0 - 2.0 * ((y as f32 + jy) / self.height as f32);
        let d = Vec3::from(self.forward) + sx * Vec3::from(self.right) + sy * Vec3::from(self.up);
        Ray {
            o: Vec3::from(self.eye),
            d: d.normalize(),
        }
    }
}

/// Where the camera sees a point: the pixel, and what light tracing and BDPT need to splat a
/// light subpath vertex there.
#[derive(Clone, Copy, Debug)]
pub struct Raster {
    pub x: u32,
    pub y: u32,
    /// Unit direction from the eye to the point.
    pub dir: Vec3,
    /// Squared distance from the eye to the point.
    pub dist2: f32,
    /// The camera's importance W(ω) = 1 / (A_pix cos³θ) (see [`Camera::importance`]).
    pub importance: f32,
}

impl Camera {
    /// Importance of the box-filtered pinhole for a direction at angle θ to the optical axis,
    /// within its pixel: W(ω) = 1 / (A_pix cos³θ), with A_pix the pixel's area on the image plane
    /// at unit distance. A pixel's value is the mean of L over its image-plane area,
    /// I = (1/A_pix) ∫ L dA_plane, and dω = cos³θ dA_plane (the plane point is 1/cosθ away and
    /// seen at angle θ), so I = ∫ W L dω. W is also the density, per solid angle, with which
    /// [`Camera::ray`] picks that direction for the pixel (a uniform point on its area).
    #[inline]
    pub fn importance(&self, cos_theta: f32) -> f32 {
        let right = Vec3::from(self.right).length();
        let up = Vec3::from(self.up).length();
        let pixel_area = 4.0 * right * up / (self.width as f32 * self.height as f32);
        1.0 / (pixel_area * cos_theta * cos_theta * cos_theta)
    }

    /// The pixel that sees point `p`, or None if `p` is behind the camera or outside the image:
    /// the inverse of [`Camera::ray`] (the direction's intersection with the image plane at unit
    /// distance, in units of the scaled right and up vectors).
    #[inline]
    pub fn raster(&self, p: Vec3) -> Option<Raster> {
        let forward = Vec3::from(self.forward);
        let d = p - Vec3::from(self.eye);
        let along = d.dot(forward);
        if along <= 0.0 {
            return None;
        }
        let (right, up) = (Vec3::from(self.right), Vec3::from(self.up));
        let plane = d / along;
        let sx = plane.dot(right) / right.length_squared();
        let sy = plane.dot(up) / up.length_squared();
        let fx = (sx + 1.0) * 0.5 * self.width as f32;
        let fy = (1.0 - sy) * 0.5 * self.height as f32;
        // Written so that NaN is outside too.
        if !(fx >= 0.0 && fx < self.width as f32 && fy >= 0.0 && fy < self.height as f32) {
            return None;
        }
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        Some(Raster {
            x: (fx as u32).min(self.width - 1),
            y: (fy as u32).min(self.height - 1),
            dir: d / dist,
            dist2,
            importance: self.importance(along / dist),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tncg15_camera(width: u32, height: u32) -> Camera {
        let desc = CameraDesc {
            eye: [-1.0, 0.0, 0.0],
            look_at: [0.0, 0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            vfov_deg: 90.0,
            note: None,
        };
        Camera::new(&desc, width, height)
    }

    /// A point on the ray through (x + jx, y + jy) is seen in pixel (x, y): `raster` inverts
    /// `ray`, away from the pixel's edges (where rounding may pick the neighbour).
    #[test]
    fn raster_finds_the_pixel_whose_ray_passes_through_a_point() {
        let cam = tncg15_camera(64, 48);
        for i in 0..2000u32 {
            let u = crate::math::sampling::Sampler::new(5, i, 0).draw4(0);
            let (x, y) = ((u[0] * 64.0) as u32, (u[1] * 48.0) as u32);
            let (jx, jy) = (0.01 + 0.98 * u[2], 0.01 + 0.98 * u[3]);
            let ray = cam.ray(x, y, jx, jy);
            let p = ray.o + ray.d * (0.5 + 7.0 * u[3]);
            let r = cam.raster(p).expect("the point is in view");
            assert_eq!((r.x, r.y), (x, y));
            assert!((r.dir - ray.d).length() < 1e-5);
        }
        assert!(
            cam.raster(Vec3::new(-2.0, 0.0, 0.0)).is_none(),
            "behind the eye"
        );
        assert!(
            cam.raster(Vec3::new(0.0, 1.5, 0.0)).is_none(),
            "outside the image"
        );
    }

    /// The importance integrates to 1 over each pixel's directions (it is a density over
    /// them): ∫ W 1{ω in pixel} dω estimated with uniform directions on the sphere, 4π · mean
    /// of W · 1{in pixel}, is 1 within 5 standard errors (of that mean) for every pixel of a
    /// 4x4 image.
    #[test]
    fn importance_integrates_to_one_over_each_pixel() {
        let cam = tncg15_camera(4, 4);
        let n = 4_000_000u32;
        let mut sum = [0.0f64; 16];
        let mut sum_sq = [0.0f64; 16];
        for i in 0..n {
            let u = crate::math::sampling::Sampler::new(11, i, 0).draw4(0);
            let z = 1.0 - 2.0 * u[0];
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (s, c) = crate::math::sampling::sin_cos_turns(u[1]);
            let d = Vec3::new(r * c, r * s, z);
            if let Some(hit) = cam.raster(Vec3::from(cam.eye) + d) {
                let w = 4.0 * std::f64::consts::PI * hit.importance as f64;
                let k = (hit.y * 4 + hit.x) as usize;
                sum[k] += w;
                sum_sq[k] += w * w;
            }
        }
        for k in 0..16 {
            let mean = sum[k] / n as f64;
            let se = ((sum_sq[k] / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(
                (mean - 1.0).abs() < 5.0 * se,
                "pixel {k}: ∫W dω = {mean:.5} ± {se:.5}"
            );
        }
    }

    #[test]
    fn tncg15_camera_matches_its_note() {
        let cam = tncg15_camera(100, 100);
        let top_left = cam.ray(0, 0, 0.0, 0.0);
        let hit = top_left.o + top_left.d / top_left.d.x;
        assert!((hit - Vec3::new(0.0, 1.0, 1.0)).length() < 1e-5, "{hit}");
        let bottom_right = cam.ray(99, 99, 1.0, 1.0);
        let hit = bottom_right.o + bottom_right.d / bottom_right.d.x;
        assert!((hit - Vec3::new(0.0, -1.0, -1.0)).length() < 1e-5, "{hit}");
    }
}
