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

// Adds sample `s` of a pixel, its radiance l, to the pixel's sums of the pass: a non-finite
// sample is counted and dropped, never accumulated (`PixelStats::add`).
fn add_sample(sums: ptr<function, PixelSums>, s: u32, l: vec3<f32>) {
    if is_finite(l) {
        (*sums).sum += l;
        (*sums).sum_sq += l * l;
        (*sums).n += 1.0;
        if (s & 1u) == 0u {
            (*sums).even_sum += l;
            (*sums).even_n += 1.0;
        }
    } else {
        (*sums).dropped += 1.0;
    }
}

// Adds the sums `taken` by an invocation for pixel (x, y) to the pixel's sums of the pass. The
// sums hold the image from row `frame.film_row` on (a film band).
fn add_to_pixel(x: u32, y: u32, taken: PixelSums) {
    let index = band_index(y * frame.camera.width + x);
    var sums = pixel_sums[index];
    sums.sum += taken.sum;
    sums.sum_sq += taken.sum_sq;
    sums.n += taken.n;
    sums.dropped += taken.dropped;
    sums.even_sum += taken.even_sum;
    sums.even_n += taken.even_n;
    pixel_sums[index] = sums;
}

// The sampler of sample `sample` of `pixel` (or light subpath `pixel`): the frame's seed and
// sampler.
fn frame_sampler(pixel: u32, sample: u32) -> Sampler {
    return Sampler(frame.seed, pixel, sample, frame.sampler);
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

// The light-subpath methods, after an iteration's light and camera passes: one invocation per pixel
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
            var sums = PixelSums();
            if splat.ok {
                add_sample(&sums, frame.first_sample, l);
            } else {
                sums.dropped = 1.0;
            }
            add_to_pixel(x, y, sums);
            if sums.n > 0.0 {
                value = l;
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
