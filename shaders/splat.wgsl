// Order-independent sums of splats: `src/transport/splat.rs`, line for line. Each splat is rounded once to
// 64-bit fixed point (24 bits after the point) and added as an integer, in two atomic<u32> words
// with a carry, so a sum does not depend on the order the splats arrive in, and equals the CPU's
// for the same splats bit for bit.
//
// The words of `tallies` (group 1, binding 1), for the P pixels of the film band
// (`frame.band_pixels`: the whole image unless it is larger than one binding) and the pass's
// MAX_PASS_SPP iteration slots: a cell of CELL_WORDS words per pixel of the band (its splats),
// then a cell per slot (that iteration's image sum over every band, and in its last word the
// most light vertices a wave of it asked for), then the light-vertex counter of the current wave,
// then the first stored vertex of each light subpath of the wave (at most P). A cell is (lo, hi)
// for red, green and blue, then an overflow flag, then a spare word.

const FRACTION_BITS: u32 = 24u;
// 2^FRACTION_BITS.
const SPLAT_SCALE: f32 = 16777216.0;
const CELL_WORDS: u32 = 8u;
const CELL_OVERFLOW: u32 = 6u;
// The image cell's last word: the most light vertices any wave of the iteration asked for.
const CELL_VERTICES: u32 = 7u;
// Iterations per pass (`MAX_PASS_SPP` in src/gpu/frame.rs).
const MAX_PASS_SPP: u32 = 64u;

// Pixels the band's splat cells cover.
fn band_pixels() -> u32 {
    return frame.band_pixels;
}

// The first word of the splat cell of the band's pixel `index` (`band_index`).
fn splat_cell(index: u32) -> u32 {
    return index * CELL_WORDS;
}

// The first word of iteration slot `slot`'s image-sum cell.
fn image_cell(slot: u32) -> u32 {
    return (band_pixels() + slot) * CELL_WORDS;
}

// The light vertices allocated so far in the current wave (cleared by the host before each).
fn vertex_counter() -> u32 {
    return (band_pixels() + MAX_PASS_SPP) * CELL_WORDS;
}

// The first stored vertex of light subpath `path`.
fn path_head(path: u32) -> u32 {
    return (band_pixels() + MAX_PASS_SPP) * CELL_WORDS + 1u + (path - frame.wave_origin);
}

struct Fixed {
    lo: u32,
    hi: u32,
    ok: bool,
}

// round(v · 2^24), ties to even, as two words, or ok = false where that is not a u64 (v
// negative, not finite, or 2^40 and more) (`to_fixed`). Every step is exact in f32.
fn to_fixed(v: f32) -> Fixed {
    let r = round(v * SPLAT_SCALE);
    if !is_finite(vec3<f32>(v)) || !(r >= 0.0 && r < 18446744073709551616.0) {
        return Fixed(0u, 0u, false);
    }
    let hi = floor(r * (1.0 / 4294967296.0));
    let lo = r - hi * 4294967296.0;
    return Fixed(u32(lo), u32(hi), true);
}

// Adds rgb to the cell at word `cell`: per channel, the low word with one atomic add, the high
// word with another plus the carry out of the low one; a value that cannot be added, or a high
// word that wraps, sets the overflow flag instead (`Splats::add`).
fn splat_add(cell: u32, rgb: vec3<f32>) {
    for (var c = 0u; c < 3u; c++) {
        let x = to_fixed(rgb[c]);
        if !x.ok {
            atomicStore(&tallies[cell + CELL_OVERFLOW], 1u);
            continue;
        }
        if x.lo == 0u && x.hi == 0u {
            continue;
        }
        let word = cell + 2u * c;
        let old_lo = atomicAdd(&tallies[word], x.lo);
        let carry = select(0u, 1u, old_lo > 0xffffffffu - x.lo);
        let add_hi = x.hi + carry;
        var wraps = carry == 1u && x.hi == 0xffffffffu;
        if add_hi != 0u {
            let old_hi = atomicAdd(&tallies[word + 1u], add_hi);
            wraps = wraps || old_hi > 0xffffffffu - add_hi;
        }
        if wraps {
            atomicStore(&tallies[cell + CELL_OVERFLOW], 1u);
        }
    }
}

struct SplatSum {
    rgb: vec3<f32>,
    // False if the sum overflowed.
    ok: bool,
}

// The cell's sum, which is then cleared for the next iteration (`Splats::take`).
fn splat_take(cell: u32) -> SplatSum {
    var rgb = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        let lo = atomicExchange(&tallies[cell + 2u * c], 0u);
        let hi = atomicExchange(&tallies[cell + 2u * c + 1u], 0u);
        rgb[c] = f32(hi) * (4294967296.0 / SPLAT_SCALE) + f32(lo) * (1.0 / SPLAT_SCALE);
    }
    let overflow = atomicExchange(&tallies[cell + CELL_OVERFLOW], 0u);
    return SplatSum(rgb, overflow == 0u);
}
