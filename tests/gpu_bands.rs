//! Any image size on the GPU: path tracing's pass sums are cut into film bands of whole rows
//! when the image is larger than one storage binding (lavapipe: 128 MiB, about 1670 x 1670), and the
//! methods that splat refuse such an image plainly before any work.

use crate::common::{default_radius, empty_temp_dir, gpu, hexray_command, Render};
use hexray::film::output::read_exr;
use hexray::film::Film;
use hexray::transport::method::Method;

/// The band tests' image: 24x19 (the height a multiple neither of 5 nor of the 8-row
/// workgroup), 3 samples, tncg15_room, seed 7.
const W: u32 = 24;
const H: u32 = 19;
const SPP: u32 = 3;

/// A GPU render of the band tests' image with `method`, in film bands of `rows` rows (None: as
/// many as the buffers hold, here the whole image), with N = `light_paths` light subpaths an
/// iteration (None: the default, one per pixel).
fn render_in_bands(method: Method, rows: Option<u32>, light_paths: Option<u32>) -> Film {
    let mut render = Render::file("scenes/tncg15_room.json")
        .size(W, H)
        .seed(7)
        .method(method);
    if light_paths.is_some() {
        let mut radius = default_radius("scenes/tncg15_room.json", method);
        radius.light_paths = light_paths;
        render = render.radius(radius);
    }
    let mut r = render.gpu_renderer();
    if let Some(rows) = rows {
        r.set_film_rows(rows);
    }
    let mut film = Film::new(W, H);
    r.render(0, SPP, &mut film).unwrap();
    film
}

/// The random streams are indexed by pixel and sample, not by band, so a film made of bands of
/// five rows (each traced, read back and folded in turn) is the unbanded film bit for bit. The
/// image's height is not a multiple of the band or of the 8-row workgroup, so the last band is
/// short and the workgroups straddle band edges. Every pixel's sums must be equal as f64 bits:
/// a band folded at the wrong row, a sample traced twice or one left out, changes them.
#[test]
fn path_tracing_in_film_bands_equals_one_band_bit_for_bit() {
    if gpu().is_none() {
        return;
    }
    let (w, spp) = (W, SPP);
    let whole = render_in_bands(Method::Path, None, None);
    let banded = render_in_bands(Method::Path, Some(5), None);
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

/// The methods that splat, in film bands of five rows: every band traces every light subpath of
/// the iteration (splatting only into the band) and its own pixels' camera subpaths, so the film
/// is the one-band film. Light tracing and BDPT: bit for bit, since splats are fixed-point sums.
/// SPPM and VCM: to f32 rounding (relative 1e-5; measured 1.2e-7), because a band's pool holds a
/// band's light subpaths at a time, so each band merges wave by wave and sums the waves' merges
/// in another order. The iterations' image means (batch means) agree to f32 rounding too (each
/// workgroup sums its pixels in f32 before its fixed-point add, and bands group the pixels into
/// other workgroups). A band that splatted only the light subpaths of its own rows, or folded
/// at the wrong row, fails. Light tracing and BDPT also with 100 light subpaths for the 456
/// pixels, which every band's pixels share.
#[test]
fn splatting_methods_in_film_bands_equal_one_band() {
    if gpu().is_none() {
        return;
    }
    let (w, spp) = (W, SPP);
    let rel = |x: f64, y: f64| (x - y).abs() / x.abs().max(1e-30);
    for (method, n) in [
        (Method::Light, None),
        (Method::Light, Some(100)),
        (Method::Bdpt, None),
        (Method::Bdpt, Some(100)),
        (Method::Sppm, None),
        (Method::Vcm, None),
    ] {
        let whole = render_in_bands(method, None, n);
        let banded = render_in_bands(method, Some(5), n);
        for (i, (a, b)) in whole.pixels.iter().zip(&banded.pixels).enumerate() {
            let at = format!("{method}: pixel {i} (row {}): {a:?} {b:?}", i as u32 / w);
            assert_eq!((a.n, b.n), (spp as u64, spp as u64), "{at}");
            if method.merges() {
                for c in 0..3 {
                    assert!(rel(a.sum[c], b.sum[c]) < 1e-5, "{at}");
                    assert!(rel(a.sum_sq[c], b.sum_sq[c]) < 1e-5, "{at}");
                }
            } else {
                assert_eq!(
                    (a.sum.map(f64::to_bits), a.sum_sq.map(f64::to_bits)),
                    (b.sum.map(f64::to_bits), b.sum_sq.map(f64::to_bits)),
                    "{at}"
                );
            }
        }
        let (a, b) = (
            whole.iteration_means.unwrap(),
            banded.iteration_means.unwrap(),
        );
        assert_eq!(a.n, b.n, "{method}");
        for c in 0..3 {
            assert!(rel(a.sum[c], b.sum[c]) < 1e-6, "{method}: {a:?} {b:?}");
            assert!(
                rel(a.sum_sq[c], b.sum_sq[c]) < 1e-6,
                "{method}: {a:?} {b:?}"
            );
        }
    }
}

/// `hexray render` of cornell_box on the GPU at one sample per pixel, from the command line;
/// the image read back, after checking its size and sample count.
fn render_one_spp(method: &str, width: usize, height: usize) -> hexray::film::output::RgbImage {
    let dir = empty_temp_dir(&format!("gpu-bands-{method}"));
    let exr = dir.join("big.exr");
    let o = hexray_command()
        .args([
            "render",
            "scenes/cornell_box.json",
            "--backend",
            "gpu",
            "--method",
            method,
        ])
        .args([
            "--width",
            &width.to_string(),
            "--height",
            &height.to_string(),
        ])
        .args(["--spp", "1", "-q", "--out"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (image, meta) = read_exr(&exr).unwrap();
    assert_eq!((image.width, image.height), (width, height));
    assert_eq!(meta.get("spp"), Some("1"));
    image
}

/// The mean of rows `y0..y1` of an image (the sum of its channels).
fn rows_mean(image: &hexray::film::output::RgbImage, y0: usize, y1: usize) -> f32 {
    let rows = &image.pixels[y0 * image.width..y1 * image.width];
    rows.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / rows.len() as f32
}

/// 3840 x 2160 (UHD) on lavapipe: path tracing's pass sums are 380 MiB, three bands of the
/// 128 MiB binding. The render succeeds from the command line, every pixel has its one sample,
/// and the first and the last band were traced (the bottom band's floor is lit as the top band's ceiling is).
#[test]
fn a_uhd_path_traced_image_renders_on_the_gpu() {
    if gpu().is_none() {
        return;
    }
    let image = render_one_spp("path", 3840, 2160);
    assert!(rows_mean(&image, 100, 101) > 0.0 && rows_mean(&image, 2100, 2101) > 0.0);
}

/// Light tracing at 2048 x 2048 on lavapipe: its splat tallies (36 bytes a pixel) are 144 MiB
/// and its pass sums (48 bytes) 192 MiB, more than the 128 MiB binding, so the image renders in
/// two film bands, each tracing every light subpath of the iteration. From the command line it
/// succeeds, every pixel has its one sample, and both bands received splats.
#[test]
fn a_splatted_image_beyond_one_binding_renders_on_the_gpu() {
    if gpu().is_none() {
        return;
    }
    let image = render_one_spp("light", 2048, 2048);
    assert!(rows_mean(&image, 0, 1024) > 0.0 && rows_mean(&image, 1900, 2048) > 0.0);
}
