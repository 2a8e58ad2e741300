//! The film (a linear-RGB pixel buffer) and writing it to PNG or OpenEXR.
//!
//! The film stores each channel as an `f32` (12 bytes a pixel): shading is done in `f64`, and
//! each pixel's final value is rounded to the nearest `f32` once, when it is stored. (That can
//! move a value across an 8-bit sRGB code boundary: measured, 1 pixel in 2.56 million of the
//! benchmark heart and 2 in 640,000 of the default scene change by one 8-bit step.) EXR output
//! is `f32` or `f16` anyway.
//!
//! Writing is atomic: the image goes to a temporary file in the target's directory, is
//! flushed to disk, and is then renamed over the target. A failed write removes the temporary
//! file and leaves any existing target untouched; [`install_interrupt_cleanup`] extends that
//! promise to Ctrl-C.

use crate::geometry::DVec3;
/// The film's pixel type: linear RGB, one `f32` a channel.
pub use glam::Vec3;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// A rendered image: `width × height` linear-RGB pixels, row-major, top row first, each
/// channel stored as an `f32` (the nearest to the `f64` value rendered).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, `width·height` of them, row-major from the top-left; linear RGB in `f32`,
    /// unclamped (values above 1, negative values and NaN are kept as rendered).
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 at the top), widened exactly from the stored
    /// `f32`s. Panics outside the image.
    pub fn get(&self, x: u32, y: u32) -> DVec3 {
        assert!(x < self.width && y < self.height, "pixel out of range");
        self.pixels[y as usize * self.width as usize + x as usize].as_dvec3()
    }

    /// Stores `value` (linear RGB) at column `x`, row `y`, each channel rounded to the nearest
    /// `f32`. Panics outside the image.
    pub fn set(&mut self, x: u32, y: u32, value: DVec3) {
        assert!(x < self.width && y < self.height, "pixel out of range");
        self.pixels[y as usize * self.width as usize + x as usize] = value.as_vec3();
    }

    /// The image as 8-bit sRGB bytes (`R, G, B` per pixel, row-major), each linear channel
    /// clamped to `[0, 1]`, sRGB-encoded and rounded to the nearest step. NaN becomes 0.
    pub fn to_srgb8(&self) -> Vec<u8> {
        use rayon::prelude::*;
        let mut bytes = vec![0u8; self.pixels.len() * 3];
        bytes
            .par_chunks_mut(3 * 4096)
            .zip(self.pixels.par_chunks(4096))
            .for_each(|(out, px)| srgb8_into(px, out));
        bytes
    }
}

/// Writes `pixels` as 8-bit sRGB bytes (`R, G, B` each) into `out`, which holds three bytes
/// a pixel.
fn srgb8_into(pixels: &[Vec3], out: &mut [u8]) {
    let table = srgb8_table();
    for (o, p) in out.chunks_exact_mut(3).zip(pixels) {
        o[0] = table.code(p.x as f64);
        o[1] = table.code(p.y as f64);
        o[2] = table.code(p.z as f64);
    }
}

/// One linear channel value as an 8-bit sRGB code: clamped to `[0, 1]` (NaN → 0), encoded
/// with the sRGB transfer curve, rounded to nearest.
pub fn linear_to_srgb8(v: f64) -> u8 {
    srgb8_table().code(v)
}

/// Buckets of equal width over `[0, 1]`; narrower than the closest pair of code
/// boundaries (1 / (12.92·255) near black), so no bucket holds two of them.
const SRGB_BUCKETS: usize = 4096;

/// Look-up tables for [`linear_to_srgb8`].
struct Srgb8Table {
    /// `first_linear[c]`: the smallest linear value whose code is `c` (index 0 unused).
    first_linear: [f64; 256],
    /// The code of each bucket's lower edge, plus one entry for 1.0 itself.
    bucket_code: [u8; SRGB_BUCKETS + 1],
}

impl Srgb8Table {
    /// [`linear_to_srgb8`]: the same answer as `srgb8_by_formula` for every input (tested),
    /// without a `powf`: the bucket of `v` gives the code at the bucket's lower edge, and one
    /// comparison with the next code's first value says whether `v` has reached it.
    #[inline]
    fn code(&self, v: f64) -> u8 {
        // Black (most of a typical background) and NaN need no look-up.
        if v.is_nan() || v <= 0.0 {
            return 0;
        }
        let v = v.min(1.0);
        let code = self.bucket_code[(v * SRGB_BUCKETS as f64) as usize];
        if code < 255 && v >= self.first_linear[code as usize + 1] {
            code + 1
        } else {
            code
        }
    }
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut first_linear = [0.0; 256];
        for (code, first) in first_linear.iter_mut().enumerate().skip(1) {
            // Non-negative doubles order like their bit patterns: bisect on the bits for
            // the first value the formula maps to `code` or above.
            let (mut lo, mut hi) = (0u64, 1f64.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if srgb8_by_formula(f64::from_bits(mid)) as usize >= code {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *first = f64::from_bits(lo);
        }
        let mut bucket_code = [0; SRGB_BUCKETS + 1];
        for (i, code) in bucket_code.iter_mut().enumerate() {
            *code = srgb8_by_formula(i as f64 / SRGB_BUCKETS as f64);
        }
        Srgb8Table {
            first_linear,
            bucket_code,
        }
    })
}

/// The sRGB transfer curve evaluated directly; the definition [`linear_to_srgb8`] follows.
fn srgb8_by_formula(v: f64) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// An 8-bit sRGB code back to a linear value in `[0, 1]` (the inverse of
/// [`linear_to_srgb8`] up to rounding).
pub fn srgb8_to_linear(c: u8) -> f64 {
    let s = c as f64 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

/// The file formats an image can be written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit RGB PNG, sRGB-encoded (`.png`).
    Png,
    /// OpenEXR RGB, linear, 32-bit float channels (`.exr`, the default for EXR).
    ExrFloat,
    /// OpenEXR RGB, linear, 16-bit half-float channels.
    ExrHalf,
}

impl ImageFormat {
    /// The format an output path asks for by its extension (case-insensitive): `.png` →
    /// [`ImageFormat::Png`], `.exr` → [`ImageFormat::ExrFloat`]; anything else is an error.
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::ExrFloat),
            _ => Err(OutputError::UnknownFormat(path.display().to_string())),
        }
    }
}

/// Why an image could not be written.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum OutputError {
    /// The extension is not .png or .exr.
    #[error("cannot tell the image format of {0}: use a .png or .exr file name")]
    UnknownFormat(String),
    /// The directory to write into does not exist or is not a directory.
    #[error("the output directory {0} does not exist")]
    NoDirectory(String),
    /// The output path names an existing directory.
    #[error("the output {0} is a directory, not a file name")]
    IsDirectory(String),
    /// Writing failed.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// Target path.
        path: String,
        /// Why.
        reason: String,
    },
}

/// The directory a file path will be written into (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Checks, before any rendering, that `path` can be written: known extension (`.png` or
/// `.exr`), an existing directory to write into in which a file can be created (tried with a
/// temporary file, removed at once), and not itself a directory. Returns the format the
/// extension selects.
pub fn check_output_path(path: &Path) -> Result<ImageFormat, OutputError> {
    let format = ImageFormat::from_path(path)?;
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(OutputError::NoDirectory(dir.display().to_string()));
    }
    if path.is_dir() {
        return Err(OutputError::IsDirectory(path.display().to_string()));
    }
    // Prove the directory is writable with the same kind of temporary file the write uses.
    let (tmp, file) = create_temp_beside(path).map_err(|e| OutputError::Write {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    drop(file);
    let _ = std::fs::remove_file(tmp);
    Ok(format)
}

/// Writes the image atomically (temporary file beside the target, then rename) in the format
/// its extension selects: PNG as 8-bit sRGB, EXR as linear 32-bit float.
pub fn write_image(image: &Image, path: &Path) -> Result<(), OutputError> {
    let format = check_output_path(path)?;
    write_image_as(image, path, format)
}

/// Writes the image atomically in the given format, whatever the extension. On success the
/// target holds the complete image; on failure the target is as it was before and no
/// temporary file is left.
pub fn write_image_as(image: &Image, path: &Path, format: ImageFormat) -> Result<(), OutputError> {
    write_atomically(path, |file| encode(image, format, file))
}

/// Writes a `width × height` PNG (8-bit sRGB, as [`write_image`] would) atomically while its
/// rows are still being made: `produce` runs on the calling thread and hands finished runs of
/// whole rows to the [`RowSink`] it is given, from any thread and in any order, each row
/// exactly once; they are compressed, in order, on a thread of their own as soon as every row
/// above them has arrived. Returns what `produce` returns once the file is complete. The
/// path is checked first (as [`check_output_path`]); on any failure, including rows missing
/// when `produce` returns, the target is left as it was and no temporary file remains.
pub fn write_png_streaming<R>(
    path: &Path,
    width: u32,
    height: u32,
    produce: impl FnOnce(&RowSink) -> R,
) -> Result<R, OutputError> {
    check_output_path(path)?;
    let mut result = None;
    write_atomically(path, |file| {
        if width == 0 || height == 0 {
            return Err(format!("the image is {width}×{height}"));
        }
        let (sender, receiver) = std::sync::mpsc::channel();
        std::thread::scope(|scope| {
            let encoder = scope.spawn(move || encode_png_rows(file, width, height, receiver));
            let sink = RowSink {
                width: width as usize,
                sender,
            };
            result = Some(produce(&sink));
            drop(sink); // ends the encoder's input
            encoder
                .join()
                .unwrap_or_else(|_| Err("the PNG encoder panicked".to_string()))
        })
    })?;
    Ok(result.expect("produce ran"))
}

/// Where [`write_png_streaming`]'s producer puts finished rows.
pub struct RowSink {
    width: usize,
    sender: std::sync::mpsc::Sender<(u32, Vec<u8>)>,
}

impl RowSink {
    /// Hands over whole rows from `first_row` down (`pixels.len()` a multiple of the width;
    /// linear RGB, converted to 8-bit sRGB here, on the caller's thread). Rows after a write
    /// error are dropped; the error is reported when the file is finished.
    pub fn rows(&self, first_row: u32, pixels: &[Vec3]) {
        debug_assert_eq!(pixels.len() % self.width, 0, "whole rows only");
        let mut bytes = vec![0u8; 3 * pixels.len()];
        srgb8_into(pixels, &mut bytes);
        let _ = self.sender.send((first_row, bytes));
    }
}

/// The encoder thread of [`write_png_streaming`]: puts the runs of rows in order as they come
/// and compresses each contiguous stretch at once.
fn encode_png_rows(
    file: File,
    width: u32,
    height: u32,
    runs: std::sync::mpsc::Receiver<(u32, Vec<u8>)>,
) -> Result<(), String> {
    let mut out = BufWriter::new(file);
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    let mut stream = writer.stream_writer().map_err(|e| e.to_string())?;
    let row_bytes = 3 * width as usize;
    let mut waiting = std::collections::BTreeMap::new();
    let mut next_row = 0u32;
    for (first_row, bytes) in runs {
        if bytes.len() % row_bytes != 0 || first_row < next_row || waiting.contains_key(&first_row)
        {
            return Err(format!("rows from {first_row} handed over twice or cut"));
        }
        waiting.insert(first_row, bytes);
        while let Some(bytes) = waiting.remove(&next_row) {
            stream.write_all(&bytes).map_err(|e| e.to_string())?;
            next_row += (bytes.len() / row_bytes) as u32;
        }
    }
    if next_row != height || !waiting.is_empty() {
        return Err(format!("only rows 0..{next_row} of {height} were made"));
    }
    stream.finish().map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    finish(out)
}

/// Runs `encode` on a fresh temporary file beside `path` and renames it over `path` when it
/// succeeds; on failure removes it and leaves `path` as it was.
fn write_atomically(
    path: &Path,
    encode: impl FnOnce(File) -> Result<(), String>,
) -> Result<(), OutputError> {
    let err = |reason: String| OutputError::Write {
        path: path.display().to_string(),
        reason,
    };
    if path.is_dir() {
        return Err(OutputError::IsDirectory(path.display().to_string()));
    }
    let (tmp_path, file) = create_temp_beside(path).map_err(|e| err(e.to_string()))?;
    register_temp(Some(tmp_path.clone()));
    let result = encode(file);
    let result = result.and_then(|()| {
        // Rename while holding the registry lock, so an interrupt either sees the temporary
        // file (and removes it) or sees nothing (the rename is done).
        let mut guard = TEMP_FILE.lock().unwrap_or_else(|p| p.into_inner());
        let renamed = std::fs::rename(&tmp_path, path).map_err(|e| e.to_string());
        *guard = None;
        renamed
    });
    if let Err(reason) = result {
        let _ = std::fs::remove_file(&tmp_path);
        register_temp(None);
        return Err(err(reason));
    }
    // Make the rename itself durable where the platform allows opening a directory.
    if let Ok(dir) = File::open(parent_dir(path)) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// An error unless the image holds `width·height ≥ 1` pixels.
fn check_size(image: &Image) -> Result<(), String> {
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.pixels.len() != w * h {
        return Err(format!(
            "the image is {}×{} but holds {} pixels",
            image.width,
            image.height,
            image.pixels.len()
        ));
    }
    Ok(())
}

/// Encodes 8-bit sRGB bytes (`R, G, B` per pixel, row-major) as PNG into `out`.
fn encode_png(bytes: &[u8], width: u32, height: u32, out: &mut impl Write) -> Result<(), String> {
    use image::ImageEncoder;
    image::codecs::png::PngEncoder::new(out)
        .write_image(bytes, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())
}

/// Flushes the buffered file and syncs it to disk.
fn finish(mut out: BufWriter<File>) -> Result<(), String> {
    out.flush().map_err(|e| e.to_string())?;
    let file = out.into_inner().map_err(|e| e.error().to_string())?;
    file.sync_all().map_err(|e| e.to_string())
}

/// Encodes the image into the (temporary) file and flushes it to disk.
fn encode(image: &Image, format: ImageFormat, file: File) -> Result<(), String> {
    check_size(image)?;
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = BufWriter::new(file);
    match format {
        ImageFormat::Png => encode_png(&image.to_srgb8(), image.width, image.height, &mut out)?,
        ImageFormat::ExrFloat => {
            use exr::prelude::*;
            let px = |v: Vec2<usize>| {
                let p = image.pixels[v.y() * w + v.x()];
                (p.x, p.y, p.z)
            };
            Image::from_channels((w, h), SpecificChannels::rgb(px))
                .write()
                .to_buffered(&mut out)
                .map_err(|e| e.to_string())?;
        }
        ImageFormat::ExrHalf => {
            use exr::prelude::*;
            let px = |v: Vec2<usize>| {
                let p = image.pixels[v.y() * w + v.x()];
                (f16::from_f32(p.x), f16::from_f32(p.y), f16::from_f32(p.z))
            };
            Image::from_channels((w, h), SpecificChannels::rgb(px))
                .write()
                .to_buffered(&mut out)
                .map_err(|e| e.to_string())?;
        }
    }
    finish(out)
}

/// Creates a fresh temporary file in the target's directory, named after the target
/// (`.NAME.PID-N.tmp`), never overwriting anything.
fn create_temp_beside(path: &Path) -> std::io::Result<(PathBuf, File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = parent_dir(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{name}.{}-{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// The temporary file being written right now, if any, for the interrupt handler.
static TEMP_FILE: Mutex<Option<PathBuf>> = Mutex::new(None);

fn register_temp(path: Option<PathBuf>) {
    *TEMP_FILE.lock().unwrap_or_else(|p| p.into_inner()) = path;
}

/// Installs (once per process) a handler for Ctrl-C (SIGINT; also SIGTERM and SIGHUP) that
/// removes the temporary file of an image being written, if any, and exits with code 130.
/// Call it from a binary before rendering; without it an interrupt may leave a temporary file
/// (never a truncated target).
/// Returns an error message when the handler could not be installed.
pub fn install_interrupt_cleanup() -> Result<(), String> {
    static INSTALLED: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    INSTALLED
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                let guard = TEMP_FILE.lock().unwrap_or_else(|p| p.into_inner());
                if let Some(tmp) = guard.as_ref() {
                    let _ = std::fs::remove_file(tmp);
                }
                // Exit while holding the lock: no rename can start after the removal.
                std::process::exit(130);
            })
            .map_err(|e| e.to_string())
        })
        .clone()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_code() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
        }
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f64::NAN), 0);
        assert_eq!(linear_to_srgb8(7.0), 255);
        assert_eq!(linear_to_srgb8(0.5), 188);
    }

    #[test]
    fn table_matches_the_formula() {
        let table = srgb8_table();
        for i in 0..SRGB_BUCKETS {
            let (lo, hi) = (table.bucket_code[i], table.bucket_code[i + 1]);
            assert!(hi - lo <= 1, "bucket {i} spans codes {lo}..={hi}");
        }
        for code in 1..=255usize {
            let first = table.first_linear[code];
            let before = f64::from_bits(first.to_bits() - 1);
            assert_eq!(linear_to_srgb8(first) as usize, code);
            assert_eq!(linear_to_srgb8(before) as usize, code - 1);
            assert_eq!(srgb8_by_formula(before) as usize, code - 1);
        }
        // A dense sweep plus pseudo-random values, including outside [0, 1].
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..2_000_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = if i % 2 == 0 {
                i as f64 / 1_000_000.0 - 0.5
            } else {
                (x >> 11) as f64 / (1u64 << 53) as f64
            };
            assert_eq!(linear_to_srgb8(v), srgb8_by_formula(v), "at {v:e}");
        }
    }

    #[test]
    fn format_from_extension() {
        assert_eq!(
            ImageFormat::from_path(Path::new("a/b.PNG")).unwrap(),
            ImageFormat::Png
        );
        assert_eq!(
            ImageFormat::from_path(Path::new("x.exr")).unwrap(),
            ImageFormat::ExrFloat
        );
        assert!(ImageFormat::from_path(Path::new("x.jpg")).is_err());
        assert!(ImageFormat::from_path(Path::new("png")).is_err());
    }

    #[test]
    fn check_rejects_missing_directory_and_directories() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope").join("a.png");
        assert!(matches!(
            check_output_path(&missing),
            Err(OutputError::NoDirectory(_))
        ));
        let sub = dir.path().join("d.png");
        std::fs::create_dir(&sub).unwrap();
        assert!(matches!(
            check_output_path(&sub),
            Err(OutputError::IsDirectory(_))
        ));
        assert!(check_output_path(&dir.path().join("ok.exr")).is_ok());
        assert!(check_output_path(Path::new("bare.png")).is_ok());
    }

    #[test]
    fn writes_png_and_exr_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = Image::new(3, 2);
        img.set(1, 0, DVec3::new(1.0, 0.5, 0.0));
        img.set(2, 1, DVec3::new(2.0, 0.25, 0.125));
        let png = dir.path().join("a.png");
        write_image(&img, &png).unwrap();
        let decoded = image::open(&png).unwrap().to_rgb8();
        assert_eq!(decoded.dimensions(), (3, 2));
        assert_eq!(decoded.get_pixel(1, 0).0, [255, 188, 0]);
        let exr_path = dir.path().join("a.exr");
        write_image(&img, &exr_path).unwrap();
        let half = dir.path().join("h.exr");
        write_image_as(&img, &half, ImageFormat::ExrHalf).unwrap();
        for p in [&exr_path, &half] {
            let read = exr::prelude::read_first_rgba_layer_from_file(
                p,
                |res, _| vec![(0.0f32, 0.0f32, 0.0f32); res.width() * res.height()],
                |v, pos, (r, g, b, _a): (f32, f32, f32, f32)| v[pos.y() * 3 + pos.x()] = (r, g, b),
            )
            .unwrap();
            assert_eq!(read.layer_data.channel_data.pixels[5], (2.0, 0.25, 0.125));
        }
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 3, "{names:?}");
    }

    #[test]
    fn streamed_png_has_the_same_pixels_whatever_the_order_of_rows() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (37u32, 29u32);
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let v = DVec3::new(x as f64 / 36.0, y as f64 / 28.0, ((x * y) % 7) as f64 / 5.0);
                img.set(x, y, v);
            }
        }
        let whole = dir.path().join("whole.png");
        write_image(&img, &whole).unwrap();
        let streamed = dir.path().join("streamed.png");
        let row = |y: u32| &img.pixels[(y * w) as usize..((y + 1) * w) as usize];
        let answer = write_png_streaming(&streamed, w, h, |sink| {
            // Bottom runs first, from two threads, in runs of uneven size.
            std::thread::scope(|s| {
                s.spawn(|| {
                    sink.rows(20, &img.pixels[(20 * w) as usize..]);
                    sink.rows(10, &img.pixels[(10 * w) as usize..(20 * w) as usize]);
                });
                s.spawn(|| {
                    for y in (0..10).rev() {
                        sink.rows(y, row(y));
                    }
                });
            });
            42
        })
        .unwrap();
        assert_eq!(answer, 42);
        let a = image::open(&whole).unwrap().to_rgb8();
        let b = image::open(&streamed).unwrap().to_rgb8();
        assert_eq!(a, b);
        let names = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(names, 2, "a temporary file was left");
    }

    #[test]
    fn streamed_png_with_missing_or_repeated_rows_fails_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("keep.png");
        std::fs::write(&target, b"old").unwrap();
        let img = Image::new(4, 3);
        let missing = write_png_streaming(&target, 4, 3, |sink| sink.rows(0, &img.pixels[..8]));
        assert!(missing.is_err());
        let twice = write_png_streaming(&target, 4, 3, |sink| {
            sink.rows(0, &img.pixels);
            sink.rows(1, &img.pixels[4..8]);
        });
        assert!(twice.is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        let nowhere = dir.path().join("no").join("such.png");
        assert!(write_png_streaming(&nowhere, 4, 3, |_| ()).is_err());
    }

    #[test]
    fn failed_write_keeps_existing_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("keep.png");
        std::fs::write(&target, b"old").unwrap();
        let bad = Image {
            width: 2,
            height: 2,
            pixels: vec![Vec3::ZERO; 3],
        };
        assert!(write_image(&bad, &target).is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
