//! 8-bit pixels: quantisation of `[0, 1]` values, PNG encoding to a reserved output, and
//! reading images within the memory limit.

use crate::error::{Error, Location, Result};
use crate::limits::MEMORY_LIMIT_BYTES;
use crate::outputs::{Named, OutputFile};
use image::{ImageEncoder, codecs::png::PngEncoder};
use std::path::Path;

/// A `[0, 1]` value to 8 bits, rounded.
#[inline]
pub fn to_u8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    (x * 255.0 + 0.5) as u8
}

/// Writes 8-bit RGBA as PNG to a reserved output (atomically, see [`OutputFile`]).
pub fn write_png(out: OutputFile, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    out.write(|w| encode_png(w, width, height, rgba))
}

/// Refuses a PNG output whose name says another format (`-o x.svg`, `x.jpg`): the bytes would
/// be PNG under that name. A `.png` name (any case), a name without an extension and `-`
/// (stdout) pass. A usage error naming the option.
pub fn check_png_name(out: Named<'_>) -> Result<()> {
    match out.path.extension() {
        Some(e) if !e.eq_ignore_ascii_case("png") => Err(Error::Usage(format!(
            "{} `{}`: this output is a PNG image; name it `.png` (or `-` for stdout)",
            out.name,
            crate::text::path(out.path)
        ))),
        _ => Ok(()),
    }
}

/// 8-bit RGBA as PNG bytes. A write error is returned as the writer gave it (its kind kept: a
/// closed stdout is a broken pipe, which ends the program quietly).
pub fn encode_png(
    w: &mut dyn std::io::Write,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> std::io::Result<()> {
    // The encoder wraps a write error in its own (kind `Other`): the first one is kept here.
    struct Keep<'a> {
        w: &'a mut dyn std::io::Write,
        error: Option<std::io::Error>,
    }
    impl Keep<'_> {
        fn kept<T>(&mut self, r: std::io::Result<T>) -> std::io::Result<T> {
            r.inspect_err(|e| {
                self.error
                    .get_or_insert_with(|| std::io::Error::new(e.kind(), e.to_string()));
            })
        }
    }
    impl std::io::Write for Keep<'_> {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let r = self.w.write(buf);
            self.kept(r)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            let r = self.w.flush();
            self.kept(r)
        }
    }
    let mut keep = Keep { w, error: None };
    let encoded = PngEncoder::new(&mut keep).write_image(
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    );
    match (encoded, keep.error) {
        (Ok(()), _) => Ok(()),
        (Err(_), Some(e)) => Err(e),
        (Err(e), None) => Err(std::io::Error::other(e)),
    }
}

/// Reads an image (format guessed from its bytes) as 8-bit straight RGBA, within
/// [`MEMORY_LIMIT_BYTES`]: the header is read first and an image whose decoding would exceed
/// the limit at its peak ([`decode_peak`]) is refused with its size before anything is
/// decoded. The decoder itself is given the same limit (not the `image` crate's smaller
/// default).
pub fn read_rgba8(path: &Path) -> Result<image::RgbaImage> {
    let (decoder, (w, h), peak) = open(path)?;
    if peak.is_none_or(|b| b > MEMORY_LIMIT_BYTES) {
        return Err(too_big(path, (w, h), peak));
    }
    image::DynamicImage::from_decoder(decoder)
        .map(image::DynamicImage::into_rgba8)
        .map_err(|e| decode_error(path, (w, h), e))
}

/// An image file's width and height and the bytes [`read_rgba8`] holds at its peak (`None`
/// past `u64`), both from the header alone (refused when its 8-bit RGBA copy alone would
/// exceed [`MEMORY_LIMIT_BYTES`], as [`read_rgba8`] refuses it): the decoded
/// buffer (16 bits a channel: up to twice the 8-bit copy) and the 8-bit RGBA copy made from it
/// (none for an image already 8-bit RGBA). What a command checks before it decodes several
/// images.
pub fn decode_peak(path: &Path) -> Result<((u32, u32), Option<u64>)> {
    let (_, size, peak) = open(path)?;
    Ok((size, peak))
}

/// Image `path` read up to its pixels (format guessed from its bytes): its decoder, limited to
/// [`MEMORY_LIMIT_BYTES`], its width and height, and its peak as [`decode_peak`] gives it;
/// refused when its 8-bit RGBA copy alone would exceed the limit.
fn open(path: &Path) -> Result<(impl image::ImageDecoder, (u32, u32), Option<u64>)> {
    use image::ImageDecoder;
    let decoder = reader(path)?
        .into_decoder()
        .map_err(|e| cannot_decode(path, e))?;
    let (w, h) = decoder.dimensions();
    let rgba = rgba8_bytes(w, h);
    if rgba.is_none_or(|b| b > MEMORY_LIMIT_BYTES) {
        return Err(too_big(path, (w, h), rgba));
    }
    let copy = if decoder.color_type() == image::ColorType::Rgba8 {
        Some(0)
    } else {
        rgba
    };
    let peak = copy.and_then(|c| c.checked_add(decoder.total_bytes()));
    Ok((decoder, (w, h), peak))
}

/// The error of decoding image `path` of `w`×`h`: past the decoder's limit, the size and the
/// limit ([`too_big`]); otherwise the decoder's message.
fn decode_error(path: &Path, (w, h): (u32, u32), e: image::ImageError) -> Error {
    match e {
        image::ImageError::Limits(_) => too_big(path, (w, h), None),
        e => cannot_decode(path, e),
    }
}

/// The bytes of a `w`×`h` 8-bit RGBA buffer (`None` past `u64`).
pub fn rgba8_bytes(w: u32, h: u32) -> Option<u64> {
    u64::from(w)
        .checked_mul(u64::from(h))
        .and_then(|n| n.checked_mul(4))
}

/// The input error of an image `path` of `w`×`h` whose decoding needs `bytes` (unknown:
/// `None`), more than [`MEMORY_LIMIT_BYTES`].
fn too_big(path: &Path, (w, h): (u32, u32), bytes: Option<u64>) -> Error {
    let size = match bytes {
        Some(b) => format!("about {:.1} GiB", b as f64 / f64::from(1u32 << 30)),
        None => "more memory".to_string(),
    };
    Error::input(
        Location::file(path),
        format!(
            "image is {w}×{h}: decoding it needs {size}, more than the {} GiB limit",
            MEMORY_LIMIT_BYTES >> 30
        ),
    )
}

/// A reader of `path` with its format guessed and the decoder limited to
/// [`MEMORY_LIMIT_BYTES`].
fn reader(path: &Path) -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>> {
    let mut r = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MEMORY_LIMIT_BYTES);
    r.limits(limits);
    Ok(r)
}

/// The input error of an image `path` that cannot be decoded.
fn cannot_decode(path: &Path, e: image::ImageError) -> Error {
    Error::input(Location::file(path), format!("cannot decode image: {e}"))
}
