// The film's side of the kernels: each pixel's samples of a pass added to its sums (folded into
// f64 by the host after the pass, `src/film/mod.rs`).

fn max_element(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

// Finite by bit pattern: the exponent is not all ones (x != x is not reliable on every backend).
fn is_finite(v: vec3<f32>) -> bool {
    let e = bitcast<vec3<u32>>(v) & vec3<u32>(0x7f800000u);
    return all(e != vec3<u32>(0x7f800000u));
}

// Adds n finite samples (their sum and sum of squares) and `dropped` non-finite ones to pixel
// (x, y)'s sums of the pass. The sums hold the image from row `frame.film_row` on (a film band).
fn add_to_pixel(x: u32, y: u32, sum: vec3<f32>, sum_sq: vec3<f32>, n: f32, dropped: f32) {
    let index = band_index(y * frame.camera.width + x);
    var sums = pixel_sums[index];
    sums.sum += sum;
    sums.sum_sq += sum_sq;
    sums.n += n;
    sums.dropped += dropped;
    pixel_sums[index] = sums;
}

// Whether image row y is in the film band.
fn in_film_band(y: u32) -> bool {
    return y >= frame.film_row && y - frame.film_row < frame.film_rows;
}

// Pixel `index`'s place in the band buffers (pass sums, splat cells, camera radiance).
fn band_index(index: u32) -> u32 {
    return index - frame.film_row * frame.camera.width;
}

// The workgroup's iteration values, summed in a fixed tree before one atomic add to the
// iteration's image sum (64 invocations of an 8 x 8 workgroup).
var<workgroup> image_partial: array<vec3<f32>, 64>;

// Light tracing and BDPT, after an iteration's light and camera passes: one invocation per pixel
// of the tile. The pixel's value for the iteration, its camera subpath's radiance (BDPT; none for
// light tracing) plus the splats it received, is one sample of the pixel, and goes into the
// iteration's image sum (batch means, src/film/mod.rs). If a wave of the iteration overflowed the
// light-vertex pool, the iteration is dropped here whole (the host traces it again); its splats
// are cleared all the same.
@compute @workgroup_size(8, 8, 1)
fn resolve_pass(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    var value = vec3<f32>(0.0);
    let overflowed = atomicLoad(&tallies[image_cell(frame.slot) + CELL_VERTICES]) > frame.vertex_capacity;
    if gid.x < frame.tile_size.x && gid.y < frame.tile_size.y {
        let x = frame.tile_origin.x + gid.x;
        let y = frame.tile_origin.y + gid.y;
        let index = y * frame.camera.width + x;
        let splat = splat_take(splat_cell(band_index(index)));
        var l = splat.rgb;
        if frame.method != METHOD_LIGHT {
            l += camera_radiance[band_index(index)].xyz;
        }
        if !overflowed {
            // A non-finite sample, or an overflowed splat sum, is counted and dropped.
            if is_finite(l) && splat.ok {
                add_to_pixel(x, y, l, l * l, 1.0, 0.0);
                value = l;
            } else {
                add_to_pixel(x, y, vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 1.0);
            }
        }
    }
    image_partial[lid] = value;
    workgroupBarrier();
    for (var stride = 32u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            image_partial[lid] += image_partial[lid + stride];
        }
        workgroupBarrier();
    }
    if lid == 0u && !overflowed {
        splat_add(image_cell(frame.slot), image_partial[0]);
    }
}
