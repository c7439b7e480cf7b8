//! Any image size on the GPU: path tracing's pass sums are cut into film bands of whole rows
//! when the image is larger than one storage binding (lavapipe: 128 MiB, 2048 x 2048), and the
//! methods that splat refuse such an image plainly before any work.

use crate::common::{empty_temp_dir, gpu, gpu_renderer, hexray_command, load};
use hexray::cpu::Faults;
use hexray::film::Film;
use hexray::method::Method;
use hexray::output::read_exr;

/// The random streams are indexed by pixel and sample, not by band, so a film made of bands of
/// five rows (each traced, read back and folded in turn) is the unbanded film bit for bit. The
/// image's height is not a multiple of the band or of the 8-row workgroup, so the last band is
/// short and the workgroups straddle band edges. Every pixel's sums must be equal as f64 bits:
/// a band folded at the wrong row, a sample traced twice or one left out, changes them.
#[test]
fn path_tracing_in_film_bands_equals_one_band_bit_for_bit() {
    let Some(gpu) = gpu() else { return };
    let (scene, flat) = load("scenes/tncg15_room.json");
    let (w, h, spp) = (24, 19, 3);
    let render = |rows: Option<u32>| {
        let mut r = gpu_renderer(gpu, &scene, &flat, w, h, 7, Method::Path, Faults::default());
        if let Some(rows) = rows {
            r.set_film_rows(rows);
        }
        let mut film = Film::new(w, h);
        r.render(0, spp, &mut film).unwrap();
        film
    };
    let whole = render(None);
    let banded = render(Some(5));
    for (i, (a, b)) in whole.pixels.iter().zip(&banded.pixels).enumerate() {
        assert_eq!(a.n, spp as u64, "pixel {i}");
        assert_eq!(
            (a.sum.map(f64::to_bits), a.sum_sq.map(f64::to_bits), a.n),
            (b.sum.map(f64::to_bits), b.sum_sq.map(f64::to_bits), b.n),
            "pixel {i} (row {})",
            i as u32 / w
        );
    }
}

/// 3840 x 2160 (UHD) on lavapipe: path tracing's pass sums are 253 MiB, two bands of the
/// 128 MiB binding. The render succeeds from the command line, and every pixel has its one sample.
#[test]
fn a_uhd_path_traced_image_renders_on_the_gpu() {
    if gpu().is_none() {
        return;
    }
    let dir = empty_temp_dir("gpu-uhd");
    let exr = dir.join("uhd.exr");
    let o = hexray_command()
        .args(["render", "scenes/cornell_box.json", "--backend", "gpu"])
        .args(["--method", "path", "--width", "3840", "--height", "2160"])
        .args(["--spp", "1", "-q", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let (image, meta) = read_exr(&exr).unwrap();
    assert_eq!((image.width, image.height), (3840, 2160));
    assert_eq!(meta.get("spp"), Some("1"));
    // Both bands were traced: the bottom band's floor is lit as the top band's ceiling light is.
    let row_mean = |y: usize| {
        let row = &image.pixels[y * 3840..(y + 1) * 3840];
        row.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / 3840.0
    };
    assert!(
        row_mean(100) > 0.0 && row_mean(2100) > 0.0,
        "{} {}",
        row_mean(100),
        row_mean(2100)
    );
}

/// The methods that splat hold the whole image in one binding (any light subpath lands on any
/// pixel): beyond it, a plain sentence that names what renders, exit 2 before any work, and no
/// raw wgpu error.
#[test]
fn a_splatting_method_beyond_the_binding_limit_is_refused_plainly() {
    if gpu().is_none() {
        return;
    }
    let dir = empty_temp_dir("gpu-size");
    let exr = dir.join("big.exr");
    let o = hexray_command()
        .args(["render", "scenes/cornell_box.json", "--backend", "gpu"])
        .args(["--method", "vcm", "--width", "3840", "--height", "2160"])
        .args(["--spp", "1", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("more than this adapter binds")
            && err.contains("--method path renders any size")
            && !err.contains("wgpu"),
        "{err}"
    );
    assert!(!exr.exists());
}
