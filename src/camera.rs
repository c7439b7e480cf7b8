//! The pinhole camera: pixel coordinates to primary rays.

use crate::geometry::Ray;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// tncg15_room's camera note: "the image plane x=0 spans y,z in [-1,1]; +y is image left,
    /// +z image top".
    #[test]
    fn tncg15_camera_matches_its_note() {
        let desc = CameraDesc {
            eye: [-1.0, 0.0, 0.0],
            look_at: [0.0, 0.0, 0.0],
            up: [0.0, 0.0, 1.0],
            vfov_deg: 90.0,
            note: None,
        };
        let cam = Camera::new(&desc, 100, 100);
        let top_left = cam.ray(0, 0, 0.0, 0.0);
        let hit = top_left.o + top_left.d / top_left.d.x;
        assert!((hit - Vec3::new(0.0, 1.0, 1.0)).length() < 1e-5, "{hit}");
        let bottom_right = cam.ray(99, 99, 1.0, 1.0);
        let hit = bottom_right.o + bottom_right.d / bottom_right.d.x;
        assert!((hit - Vec3::new(0.0, -1.0, -1.0)).length() < 1e-5, "{hit}");
    }
}
