//! Image files: linear float EXR with the render's metadata, an sRGB PNG for people, and the
//! variance of the mean as a second EXR. Every file is written to a temporary name in the same
//! directory and renamed into place, so a reader never sees half a file and an interrupted
//! write leaves the previous file intact.

use anyhow::{bail, Context, Result};
use exr::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a render file records about how it was made.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metadata {
    /// Ordered key/value pairs, written as EXR string attributes named `hexray:<key>`.
    pub fields: BTreeMap<String, String>,
}

impl Metadata {
    pub fn set(&mut self, key: &str, value: impl ToString) {
        self.fields.insert(key.to_string(), value.to_string());
    }
    pub fn get(&self, key: &str) -> Option<&str> {
        self.fields.get(key).map(String::as_str)
    }
}

/// The EXR attribute that holds the render's metadata.
pub const METADATA_ATTRIBUTE: &str = "hexray";

/// A linear RGB image in memory, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// The three paths written for `--out DIR/NAME.exr`: the EXR, `NAME.png` and `NAME_var.exr`.
pub fn output_paths(out: &Path) -> (PathBuf, PathBuf, PathBuf) {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".into());
    let dir = out.parent().unwrap_or(Path::new(""));
    (
        out.to_path_buf(),
        dir.join(format!("{stem}.png")),
        dir.join(format!("{stem}_var.exr")),
    )
}

/// Checks, before any rendering, that the outputs for `--out out` can be written: no output
/// path is an existing directory, the folder exists or can be made, and a file can be created in
/// it (so `/proc/x.exr`, a path under a regular file and a read-only folder are refused at
/// once, not after the render). The probe file is removed again.
pub fn check_writable(out: &Path, variance: bool) -> Result<()> {
    let (exr, png, var) = output_paths(out);
    let mut paths = vec![&exr, &png];
    if variance {
        paths.push(&var);
    }
    for p in paths {
        if p.is_dir() {
            bail!("{} is a directory; give --out a file name", p.display());
        }
    }
    let dir = exr.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(d) = dir {
        std::fs::create_dir_all(d)
            .with_context(|| format!("cannot create the output folder {}", d.display()))?;
    }
    let dir = dir.unwrap_or(Path::new("."));
    let probe = dir.join(format!(".hexray-probe{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .with_context(|| format!("cannot write in the output folder {}", dir.display()))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes `bytes_of(tmp)` with `write` and renames it over `path`. A `path` that is neither a
/// regular file nor a folder (a device such as `/dev/null`, a named pipe) is written in place:
/// renaming over it would replace the device with a file.
pub(crate) fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if is_special(path) {
        return write(path);
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(d) = dir {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path)
            .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Whether `path` (followed through links) exists and is neither a regular file nor a folder.
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Writes 8-bit RGB pixels (row 0 at the top) as a PNG, atomically.
pub fn write_rgb8_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<()> {
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            rgb,
            width,
            height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .with_context(|| format!("writing {}", tmp.display()))
    })
}

/// Writes a text file (JSON, CSV) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |tmp| {
        std::fs::write(tmp, text).with_context(|| format!("writing {}", tmp.display()))
    })
}

/// Writes a linear float RGB EXR (32-bit float channels, lossless ZIP) with the metadata as one
/// string attribute `hexray`, a `key=value` line per field in key order. (One attribute, not one
/// per key: the exr crate keeps custom attributes in a randomly seeded `HashMap` and writes them
/// in its iteration order, so several would make the same image a different file each time.)
pub fn write_exr(path: &Path, image: &RgbImage, meta: &Metadata) -> Result<()> {
    write_atomically(path, |tmp| {
        let (w, h) = (image.width, image.height);
        let pixels = &image.pixels;
        let channels = SpecificChannels::rgb(|p: Vec2<usize>| -> (f32, f32, f32) {
            let [r, g, b] = pixels[p.y() * w + p.x()];
            (r, g, b)
        });
        let mut attrs = LayerAttributes::named("hexray");
        attrs.software_name = Some(Text::from(concat!("hexray ", env!("CARGO_PKG_VERSION"))));
        let lines: String = meta
            .fields
            .iter()
            .map(|(k, v)| format!("{k}={}\n", v.replace('\n', " ")))
            .collect();
        // EXR text is Latin-1: anything beyond U+00FF (a scene path in Japanese) is escaped,
        // never a panic after the render.
        let lines = latin1_escape(&lines);
        attrs.other.insert(
            Text::from(METADATA_ATTRIBUTE),
            exr::meta::attribute::AttributeValue::Text(Text::from(lines.as_str())),
        );
        let layer = Layer::new((w, h), attrs, Encoding::SMALL_LOSSLESS, channels);
        Image::from_layer(layer)
            .write()
            .to_file(tmp)
            .with_context(|| format!("writing {}", tmp.display()))
    })
}

/// `s` in characters an EXR text attribute holds (Latin-1): `\` becomes `\\`, and each
/// character above U+00FF `\u{XXXX}` (its code point in hex); [`latin1_unescape`] undoes it.
pub fn latin1_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            c if (c as u32) <= 0xff => out.push(c),
            c => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
        }
    }
    out
}

/// The inverse of [`latin1_escape`]; anything that is not one of its escapes stays as it is.
pub fn latin1_unescape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find('\\') {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        if let Some(after) = tail.strip_prefix("\\\\") {
            out.push('\\');
            rest = after;
            continue;
        }
        let code = tail
            .strip_prefix("\\u{")
            .and_then(|t| t.split_once('}'))
            .and_then(|(hex, after)| {
                let c = char::from_u32(u32::from_str_radix(hex, 16).ok()?)?;
                Some((c, after))
            });
        match code {
            Some((c, after)) => {
                out.push(c);
                rest = after;
            }
            None => {
                out.push('\\');
                rest = &tail[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

/// The `hexray` metadata of an EXR's first header, without reading its pixels.
pub fn read_exr_metadata(path: &Path) -> Result<Metadata> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .with_context(|| format!("reading {}", path.display()))?;
    let header = meta
        .headers
        .first()
        .with_context(|| format!("{}: no image in the file", path.display()))?;
    Ok(metadata_of(&header.own_attributes.other))
}

/// The render metadata among an EXR header's custom attributes.
fn metadata_of(
    attributes: &std::collections::HashMap<
        exr::meta::attribute::Text,
        exr::meta::attribute::AttributeValue,
    >,
) -> Metadata {
    let mut meta = Metadata::default();
    for (k, v) in attributes {
        if let (METADATA_ATTRIBUTE, exr::meta::attribute::AttributeValue::Text(t)) =
            (k.to_string().as_str(), v)
        {
            for line in latin1_unescape(&t.to_string()).lines() {
                if let Some((key, value)) = line.split_once('=') {
                    meta.set(key, value);
                }
            }
        }
    }
    meta
}

/// The largest ratio of decoded to stored bytes an EXR compression reaches: deflate (ZIP,
/// ZIPS) stores at best 1032 bytes in one; RLE, PIZ, PXR24 and B44 far fewer.
const MAX_EXR_EXPANSION: u64 = 1100;

/// Checks an EXR's header against the file's size before any pixel memory is allocated: the
/// chunk offset table (8 bytes per chunk) must fit in the file, and the decoded pixels must not
/// exceed what any compression could have stored in it. A 1.3 kB file whose header claims
/// 100000 x 100000 is refused here instead of asking for 120 GB.
pub fn check_exr_size(path: &Path) -> Result<()> {
    let file_len = std::fs::metadata(path)
        .with_context(|| format!("reading {}", path.display()))?
        .len();
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .with_context(|| format!("reading {}", path.display()))?;
    for header in meta.headers.iter() {
        let (w, h) = (
            header.layer_size.width() as u64,
            header.layer_size.height() as u64,
        );
        let sample_bytes: u64 = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum();
        let decoded = w.saturating_mul(h).saturating_mul(sample_bytes.max(1));
        let table = (header.chunk_count as u64).saturating_mul(8);
        if table > file_len || decoded > file_len.saturating_mul(MAX_EXR_EXPANSION) {
            bail!(
                "{}: the header claims {w}x{h} pixels ({decoded} bytes decoded, {} chunks), more \
                 than a file of {file_len} bytes can hold; the file is damaged or crafted",
                path.display(),
                header.chunk_count
            );
        }
    }
    Ok(())
}

/// Reads the first RGB(A) layer of an EXR and its `hexray:` metadata.
pub fn read_exr(path: &Path) -> Result<(RgbImage, Metadata)> {
    check_exr_size(path)?;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| RgbImage {
            width: res.width(),
            height: res.height(),
            pixels: vec![[0.0; 3]; res.width() * res.height()],
        },
        |img: &mut RgbImage, p: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[p.y() * w + p.x()] = [r, g, b];
        },
    )
    .with_context(|| format!("reading {}", path.display()))?;
    let meta = metadata_of(&image.layer_data.attributes.other);
    Ok((image.layer_data.channel_data.pixels, meta))
}

/// Reads a NumPy `.npy` array of shape (height, width, 3), float32 or float64, C order, row 0
/// at the top: the format of the external references in `shared/references/`.
pub fn read_npy_rgb(path: &Path) -> Result<RgbImage> {
    let bytes = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let npy =
        npyz::NpyFile::new(&bytes[..]).with_context(|| format!("parsing {}", path.display()))?;
    let shape = npy.shape().to_vec();
    if shape.len() != 3 || shape[2] != 3 {
        bail!(
            "{}: expected shape (height, width, 3), found {shape:?}",
            path.display()
        );
    }
    if npy.order() != npyz::Order::C {
        bail!(
            "{}: Fortran-ordered arrays are not supported; save it in C order",
            path.display()
        );
    }
    let (height, width) = (shape[0] as usize, shape[1] as usize);
    // The shape against the bytes that hold it, before allocating for it.
    let item = if matches!(npy.dtype(), npyz::DType::Plain(t) if t.size_field() == 8) {
        8
    } else {
        4
    };
    let needed = shape.iter().try_fold(item as u64, |a, &d| a.checked_mul(d));
    if needed.is_none_or(|n| n > bytes.len() as u64) {
        bail!(
            "{}: shape {shape:?} needs more bytes than the file's {}; the file is damaged",
            path.display(),
            bytes.len()
        );
    }
    let data: Vec<f32> = match npy.dtype() {
        npyz::DType::Plain(t) if t.size_field() == 8 => npy
            .into_vec::<f64>()?
            .into_iter()
            .map(|x| x as f32)
            .collect(),
        _ => npy
            .into_vec::<f32>()
            .with_context(|| format!("{}: expected float32 or float64 data", path.display()))?,
    };
    Ok(RgbImage {
        width,
        height,
        pixels: data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    })
}

/// The sRGB transfer function (IEC 61966-2-1) on a linear value in [0, 1].
fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes an 8-bit sRGB PNG for people: linear radiance times 2^exposure, clamped to [0, 1],
/// then sRGB-encoded. The only tone mapping in hexray, and only here.
pub fn write_png(path: &Path, image: &RgbImage, exposure: f32) -> Result<()> {
    if image.width == 0 || image.height == 0 {
        bail!("empty image");
    }
    let scale = exposure.exp2();
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| (srgb_encode((c * scale).clamp(0.0, 1.0)) * 255.0 + 0.5) as u8))
        .collect();
    write_atomically(path, |tmp| {
        image::save_buffer_with_format(
            tmp,
            &bytes,
            image.width as u32,
            image.height as u32,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .with_context(|| format!("writing {}", tmp.display()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An output named `/dev/null` is written into the device, not renamed over it (which would
    /// leave a regular file in its place); a regular file is still replaced whole.
    #[cfg(unix)]
    #[test]
    fn writing_to_a_device_leaves_the_device_in_place() {
        use std::os::unix::fs::FileTypeExt;
        let null = Path::new("/dev/null");
        assert!(is_special(null));
        write_text(null, "{}").unwrap();
        let kind = std::fs::metadata(null).unwrap().file_type();
        assert!(kind.is_char_device(), "/dev/null is no longer a device");

        let dir = std::env::temp_dir().join(format!("hexray-special-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("out.json");
        assert!(!is_special(&file), "a path that does not exist yet");
        write_text(&file, "old and longer").unwrap();
        assert!(!is_special(&file));
        write_text(&file, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn exr_round_trips_pixels_and_metadata() {
        let dir = std::env::temp_dir().join(format!("hexray-exr-{}", std::process::id()));
        let path = dir.join("a.exr");
        let image = RgbImage {
            width: 3,
            height: 2,
            pixels: (0..6).map(|i| [i as f32, 0.5, 1e-7 * i as f32]).collect(),
        };
        let mut meta = Metadata::default();
        meta.set("spp", 64);
        meta.set("scene_sha1", "abc");
        write_exr(&path, &image, &meta).unwrap();
        let (back, back_meta) = read_exr(&path).unwrap();
        assert_eq!(back, image);
        assert_eq!(back_meta, meta);
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn latin1_escapes_round_trip() {
        for s in [
            "plain",
            "ümlaut ÿ",
            "場景/部屋.json",
            "back\\slash \\u{41}",
            "emoji 🦀\\",
        ] {
            let e = latin1_escape(s);
            assert!(e.chars().all(|c| (c as u32) <= 0xff), "{e}");
            assert_eq!(latin1_unescape(&e), s);
        }
    }

    #[test]
    fn output_paths_follow_the_exr_name() {
        let (e, p, v) = output_paths(Path::new("out/room.exr"));
        assert_eq!(e, Path::new("out/room.exr"));
        assert_eq!(p, Path::new("out/room.png"));
        assert_eq!(v, Path::new("out/room_var.exr"));
    }
}
