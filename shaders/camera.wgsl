// The pinhole camera: `src/transport/camera.rs`, line for line.

// The ray through image position (x + jx, y + jy), pixel (0, 0) at the top left (`Camera::ray`).
fn camera_ray(camera: Camera, x: u32, y: u32, jx: f32, jy: f32) -> Ray {
    let sx = 2.0 * ((f32(x) + jx) / f32(camera.width)) - 1.0;
    let sy = 1.0 - 2.0 * ((f32(y) + jy) / f32(camera.height));
    let d = camera.forward + sx * camera.right + sy * camera.up;
    return Ray(camera.eye, normalize(d));
}

// Importance of the box-filtered pinhole at cos theta to the axis, within its pixel:
// W = 1 / (A_pix cos^3 theta), also the solid-angle density of the pixel's ray directions
// (`Camera::importance`).
fn camera_importance(camera: Camera, cos_theta: f32) -> f32 {
    let pixel_area = 4.0 * length(camera.right) * length(camera.up) / (f32(camera.width) * f32(camera.height));
    return 1.0 / (pixel_area * cos_theta * cos_theta * cos_theta);
}

// Where the camera sees a point (`Raster`): `seen` is false behind the camera or outside the
// image.
struct Raster {
    seen: bool,
    x: u32,
    y: u32,
    // Unit direction from the eye to the point.
    dir: vec3<f32>,
    dist2: f32,
    importance: f32,
}

// The pixel that sees point p: the inverse of camera_ray (`Camera::raster`).
fn camera_raster(camera: Camera, p: vec3<f32>) -> Raster {
    var r = Raster(false, 0u, 0u, vec3<f32>(0.0), 0.0, 0.0);
    let d = p - camera.eye;
    let along = dot(d, camera.forward);
    if along <= 0.0 {
        return r;
    }
    let plane = d / along;
    let sx = dot(plane, camera.right) / dot(camera.right, camera.right);
    let sy = dot(plane, camera.up) / dot(camera.up, camera.up);
    let fx = (sx + 1.0) * 0.5 * f32(camera.width);
    let fy = (1.0 - sy) * 0.5 * f32(camera.height);
    if !(fx >= 0.0 && fx < f32(camera.width) && fy >= 0.0 && fy < f32(camera.height)) {
        return r;
    }
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    r.seen = true;
    r.x = min(u32(fx), camera.width - 1u);
    r.y = min(u32(fy), camera.height - 1u);
    r.dir = d / dist;
    r.dist2 = dist2;
    r.importance = camera_importance(camera, along / dist);
    return r;
}
