//! Encoders: an [`Image`] to PNG (8-bit sRGB) or OpenEXR (linear float) on any writer; an
//! image with alpha becomes an RGBA PNG (straight alpha) or an RGBA EXR (premultiplied).

use super::png_filter::AdaptiveRowFilter;
use super::{srgb8_into, srgba8_into, AtomicFile, Image, Vec3};
use std::io::{Seek, Write};
use std::path::Path;

/// The file formats an image can be written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit RGB PNG, sRGB-encoded (`.png`); RGBA with straight alpha for an image with alpha.
    Png,
    /// OpenEXR RGB, linear, 32-bit float channels (`.exr`, the default for EXR); RGBA with
    /// premultiplied colours for an image with alpha.
    ExrFloat,
    /// OpenEXR RGB (or premultiplied RGBA), linear, 16-bit half-float channels.
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

/// Why an image could not be encoded or written.
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
    /// Writing a file failed.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// Target path.
        path: String,
        /// Why.
        reason: String,
    },
    /// Encoding to a writer failed (the writer's error, or an image with no pixels).
    #[error("cannot encode the image: {0}")]
    Encode(String),
}

impl OutputError {
    /// An encoding error restated as a failure to write `path`; other errors unchanged.
    fn writing(self, path: &Path) -> Self {
        match self {
            OutputError::Encode(reason) => OutputError::Write {
                path: path.display().to_string(),
                reason,
            },
            other => other,
        }
    }
}

fn encode_error(e: impl std::fmt::Display) -> OutputError {
    OutputError::Encode(e.to_string())
}

/// Writes the image atomically (temporary file beside the target, then rename) in the format
/// its extension selects: PNG as 8-bit sRGB, EXR as linear 32-bit float.
pub fn write_image(image: &Image, path: &Path) -> Result<(), OutputError> {
    let format = ImageFormat::from_path(path)?;
    write_image_as(image, path, format)
}

/// Writes the image atomically in the given format, whatever the extension. On success the
/// target holds the complete image; on failure the target is as it was before and no
/// temporary file is left.
pub fn write_image_as(image: &Image, path: &Path, format: ImageFormat) -> Result<(), OutputError> {
    let mut file = AtomicFile::create(path)?;
    encode(image, format, &mut file).map_err(|e| e.writing(path))?;
    file.commit()
}

/// Encodes the image in `format` into `out` (seekable because OpenEXR's writer needs it).
pub fn encode(
    image: &Image,
    format: ImageFormat,
    out: impl Write + Seek,
) -> Result<(), OutputError> {
    match format {
        ImageFormat::Png => encode_png(image, out),
        ImageFormat::ExrFloat => encode_exr(image, false, out),
        ImageFormat::ExrHalf => encode_exr(image, true, out),
    }
}

/// A line of text stored in an image file under a name: a PNG `tEXt` chunk (Latin-1 name of
/// 1 to 79 characters) or an OpenEXR text attribute. [`read_tag`] reads it back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileTag<'a> {
    /// The chunk's keyword or the attribute's name.
    pub name: &'a str,
    /// The text.
    pub text: &'a str,
}

/// [`encode`] with `tag` stored in the file (a PNG through [`encode_png_streaming_tagged`],
/// handed all rows at once).
pub fn encode_tagged(
    image: &Image,
    format: ImageFormat,
    tag: Option<FileTag>,
    out: impl Write + Seek + Send,
) -> Result<(), OutputError> {
    match format {
        ImageFormat::Png => {
            check_size(image)?;
            let ((), written) = encode_png_streaming_tagged(
                out,
                image.width,
                image.height,
                image.alpha.is_some(),
                tag,
                |sink| sink.rows(0, &image.pixels, image.alpha.as_deref()),
            );
            written
        }
        ImageFormat::ExrFloat => encode_exr_tagged(image, false, tag, out),
        ImageFormat::ExrHalf => encode_exr_tagged(image, true, tag, out),
    }
}

/// The text stored under `name` in the PNG or OpenEXR file at `path` (by its extension), or
/// `None` when the file cannot be read or holds no such text.
pub fn read_tag(path: &Path, name: &str) -> Option<String> {
    let file = std::io::BufReader::new(std::fs::File::open(path).ok()?);
    match ImageFormat::from_path(path).ok()? {
        ImageFormat::Png => read_png_tag(file, name),
        ImageFormat::ExrFloat | ImageFormat::ExrHalf => {
            use exr::prelude::{AttributeValue, Text};
            let meta = exr::meta::MetaData::read_from_buffered(file, false).ok()?;
            let header = meta.headers.first()?;
            let key = Text::from(name);
            let found = header
                .shared_attributes
                .other
                .get(&key)
                .or_else(|| header.own_attributes.other.get(&key));
            match found {
                Some(AttributeValue::Text(t)) => Some(t.to_string()),
                _ => None,
            }
        }
    }
}

/// The text of the `tEXt` chunk `name` that a PNG (or APNG) stream holds before its image
/// data, if any; `None` for a stream that is not a PNG.
pub(crate) fn read_png_tag(
    stream: impl std::io::BufRead + std::io::Seek,
    name: &str,
) -> Option<String> {
    let reader = png::Decoder::new(stream).read_info().ok()?;
    reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == name)
        .map(|t| t.text.clone())
}

/// An error unless the image holds `width·height ≥ 1` pixels.
fn check_size(image: &Image) -> Result<(), OutputError> {
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.pixels.len() != w * h {
        return Err(OutputError::Encode(format!(
            "the image is {}×{} but holds {} pixels",
            image.width,
            image.height,
            image.pixels.len()
        )));
    }
    Ok(())
}

/// Encodes the image as an 8-bit sRGB PNG (each channel clamped to `[0, 1]`) into `out`: RGB,
/// or for an image with alpha RGBA with straight alpha ([`Image::to_srgba8`]).
pub fn encode_png(image: &Image, mut out: impl Write) -> Result<(), OutputError> {
    use image::ImageEncoder;
    check_size(image)?;
    let (bytes, colour) = match image.alpha {
        None => (image.to_srgb8(), image::ExtendedColorType::Rgb8),
        Some(_) => (image.to_srgba8(), image::ExtendedColorType::Rgba8),
    };
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(&bytes, image.width, image.height, colour)
        .map_err(encode_error)?;
    out.flush().map_err(encode_error)
}

/// How kardia's OpenEXR files are laid out: the `exr` crate's default (RLE compression in
/// 64×64 tiles) with the blocks in increasing order. The crate compresses blocks on many
/// threads; with an unspecified order it writes each as it finishes, so the same image gave
/// different bytes from run to run. In increasing order the file is one sequence of bytes for
/// one image, whatever the threads.
pub(crate) fn exr_encoding() -> exr::image::Encoding {
    exr::image::Encoding {
        line_order: exr::meta::attribute::LineOrder::Increasing,
        ..exr::image::Encoding::FAST_LOSSLESS
    }
}

/// Encodes the image as linear-RGB OpenEXR into `out`: 32-bit float channels, or 16-bit half
/// floats when `half` (values beyond the half range stored as `±65504`, never infinity). An
/// image with alpha gets an A channel too, its colours premultiplied (OpenEXR's convention).
/// The same image always gives the same bytes (blocks in increasing order, [`exr_encoding`]).
pub fn encode_exr(image: &Image, half: bool, out: impl Write + Seek) -> Result<(), OutputError> {
    encode_exr_tagged(image, half, None, out)
}

/// [`encode_exr`] with `tag` stored as a text attribute of the image.
pub fn encode_exr_tagged(
    image: &Image,
    half: bool,
    tag: Option<FileTag>,
    mut out: impl Write + Seek,
) -> Result<(), OutputError> {
    use exr::prelude::*;
    check_size(image)?;
    let w = image.width as usize;
    let at = |v: Vec2<usize>| image.pixels[v.y() * w + v.x()];
    let size = (w, image.height as usize);
    let max = f16::MAX.to_f32();
    let h = |c: f32| f16::from_f32(c.clamp(-max, max));
    // Every channel layout is its own type: one expansion each.
    macro_rules! write_exr {
        ($channels:expr) => {{
            let mut exr = Image::from_encoded_channels(size, exr_encoding(), $channels);
            if let Some(tag) = tag {
                exr.attributes.other.insert(
                    Text::from(tag.name),
                    AttributeValue::Text(Text::from(tag.text)),
                );
            }
            exr.write().to_buffered(&mut out).map_err(encode_error)?;
        }};
    }
    match (&image.alpha, half) {
        (Some(alpha), true) => write_exr!(SpecificChannels::rgba(|v: Vec2<usize>| {
            let p = at(v);
            let a = alpha[v.y() * w + v.x()];
            (h(p.x), h(p.y), h(p.z), f16::from_f32(a))
        })),
        (Some(alpha), false) => write_exr!(SpecificChannels::rgba(|v: Vec2<usize>| {
            let p = at(v);
            (p.x, p.y, p.z, alpha[v.y() * w + v.x()])
        })),
        (None, true) => write_exr!(SpecificChannels::rgb(|v: Vec2<usize>| {
            let p = at(v);
            (h(p.x), h(p.y), h(p.z))
        })),
        (None, false) => write_exr!(SpecificChannels::rgb(|v: Vec2<usize>| {
            let p = at(v);
            (p.x, p.y, p.z)
        })),
    }
    out.flush().map_err(encode_error)
}

/// Encodes a `width × height` PNG (8-bit sRGB, fast compression; RGBA with straight alpha
/// when `alpha`, else RGB) into `out` while its rows are
/// still being made: `produce` runs on the calling thread and hands finished runs of whole rows
/// to the [`RowSink`] it is given, from any thread and in any order, each row exactly once;
/// they are compressed, in order, on a thread of their own as soon as every row above them has
/// arrived. Returns what `produce` returned, and whether the PNG was completed: an error when
/// writing failed or rows were missing or repeated when `produce` returned (then `out` holds
/// an unfinished PNG: write to an [`AtomicFile`] and commit only on success).
pub fn encode_png_streaming<R>(
    out: impl Write + Send,
    width: u32,
    height: u32,
    alpha: bool,
    produce: impl FnOnce(&RowSink) -> R,
) -> (R, Result<(), OutputError>) {
    encode_png_streaming_tagged(out, width, height, alpha, None, produce)
}

/// [`encode_png_streaming`] with `tag` stored in a `tEXt` chunk before the pixels.
pub fn encode_png_streaming_tagged<R>(
    out: impl Write + Send,
    width: u32,
    height: u32,
    alpha: bool,
    tag: Option<FileTag>,
    produce: impl FnOnce(&RowSink) -> R,
) -> (R, Result<(), OutputError>) {
    let queue = std::sync::Arc::new(RowQueue::default());
    std::thread::scope(|scope| {
        let runs = RunsInOrder(queue.clone());
        let encoder = scope.spawn(move || encode_png_rows(out, width, height, alpha, tag, runs));
        let sink = RowSink {
            width: width as usize,
            alpha,
            queue,
        };
        let result = produce(&sink);
        drop(sink); // ends the encoder's input
        let written = encoder
            .join()
            .unwrap_or_else(|_| Err("the PNG encoder panicked".to_string()))
            .map_err(OutputError::Encode);
        (result, written)
    })
}

/// Where [`encode_png_streaming`]'s producer puts finished rows.
pub struct RowSink {
    width: usize,
    /// Whether the PNG is RGBA.
    alpha: bool,
    queue: std::sync::Arc<RowQueue>,
}

impl RowSink {
    /// Hands over whole rows from `first_row` down (`pixels.len()` a multiple of the width;
    /// linear RGB, converted to 8-bit sRGB here, on the caller's thread) with their coverage
    /// (`alpha`, one value a pixel, premultiplied `pixels`; `None`: opaque) for an RGBA PNG,
    /// which an RGB PNG ignores. Rows after a write error are dropped; the error is reported
    /// when the file is finished.
    pub fn rows(&self, first_row: u32, pixels: &[Vec3], alpha: Option<&[f32]>) {
        debug_assert_eq!(pixels.len() % self.width.max(1), 0, "whole rows only");
        let bytes = if self.alpha {
            let mut bytes = vec![0u8; 4 * pixels.len()];
            srgba8_into(pixels, alpha, &mut bytes);
            bytes
        } else {
            let mut bytes = vec![0u8; 3 * pixels.len()];
            srgb8_into(pixels, &mut bytes);
            bytes
        };
        self.queue.push(first_row, bytes);
    }
}

impl Drop for RowSink {
    /// No more rows: the encoder finishes the file with what it has (also when the producer
    /// panicked, so that the encoder's thread ends).
    fn drop(&mut self) {
        self.queue.lock().closed = true;
        self.queue.arrived.notify_one();
    }
}

/// The runs of rows handed over and not yet taken by the encoder, shared by the producer's
/// threads and the encoder's.
#[derive(Default)]
struct RowQueue {
    state: std::sync::Mutex<QueueState>,
    /// Told when the run the encoder needs next has arrived, and when the input ends.
    arrived: std::sync::Condvar,
}

#[derive(Default)]
struct QueueState {
    /// Runs handed over since the encoder last looked: (first row, sRGB bytes).
    runs: Vec<(u32, Vec<u8>)>,
    /// The first row the encoder has not compressed nor holds: a run starting here wakes it.
    /// Runs arriving out of order do not: the encoder could not use them yet, and on two
    /// cores waking it only takes a core from a render thread.
    wanted: u32,
    /// The producer is done.
    closed: bool,
    /// The encoder has stopped (finished or failed): rows are dropped.
    stopped: bool,
}

impl RowQueue {
    fn lock(&self) -> std::sync::MutexGuard<'_, QueueState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Queues a run, waking the encoder if it is the one it waits for; returns whether it
    /// did (a run handed over after the encoder stopped is dropped and wakes nothing).
    fn push(&self, first_row: u32, bytes: Vec<u8>) -> bool {
        let mut state = self.lock();
        if state.stopped {
            return false;
        }
        let wanted = first_row == state.wanted;
        state.runs.push((first_row, bytes));
        drop(state);
        if wanted {
            self.arrived.notify_one();
        }
        wanted
    }
}

/// The encoder's side of a [`RowQueue`]: runs in the order they arrived, handed over once the
/// encoder can use one (or the input has ended); marks the queue stopped when dropped.
struct RunsInOrder(std::sync::Arc<RowQueue>);

impl RunsInOrder {
    /// Waits until a run starting at `wanted` has arrived or the input has ended; returns the
    /// runs that arrived meanwhile (in arrival order) and whether the input has ended.
    fn next_batch(&self, wanted: u32) -> (Vec<(u32, Vec<u8>)>, bool) {
        let mut state = self.0.lock();
        state.wanted = wanted;
        loop {
            if state.closed || state.runs.iter().any(|run| run.0 == wanted) {
                return (std::mem::take(&mut state.runs), state.closed);
            }
            state = self
                .0
                .arrived
                .wait(state)
                .unwrap_or_else(|e| e.into_inner());
        }
    }
}

impl Drop for RunsInOrder {
    fn drop(&mut self) {
        let mut state = self.0.lock();
        state.stopped = true;
        state.runs.clear();
    }
}

/// The encoder thread of [`encode_png_streaming`]: puts the runs of rows in order as they
/// come and compresses each contiguous stretch at once.
fn encode_png_rows(
    out: impl Write,
    width: u32,
    height: u32,
    alpha: bool,
    tag: Option<FileTag>,
    runs: RunsInOrder,
) -> Result<(), String> {
    let mut png = PngRows::start(out, width, height, alpha, tag)?;
    let row_bytes = png.row_len();
    let mut waiting = std::collections::BTreeMap::new();
    let mut next_row = 0u32;
    loop {
        let (arrived, closed) = runs.next_batch(next_row);
        for (first_row, bytes) in arrived {
            if bytes.len() % row_bytes != 0
                || first_row < next_row
                || waiting.contains_key(&first_row)
            {
                return Err(format!("rows from {first_row} handed over twice or cut"));
            }
            waiting.insert(first_row, bytes);
        }
        while let Some(bytes) = waiting.remove(&next_row) {
            png.rows(&bytes).map_err(|e| e.to_string())?;
            next_row += (bytes.len() / row_bytes) as u32;
        }
        if closed {
            break;
        }
    }
    drop(runs);
    if next_row != height || !waiting.is_empty() {
        return Err(format!("only rows 0..{next_row} of {height} were made"));
    }
    png.finish()
}

/// Encodes `width × height` rows of 8-bit sRGB bytes (RGB, or straight-alpha RGBA when
/// `alpha`; `rows.len()` = width · height · channels) into `out` as [`encode_png_streaming`]
/// does: the same file bytes for the same bytes and `tag`, on this thread.
pub fn encode_png_srgb8(
    rows: &[u8],
    width: u32,
    height: u32,
    alpha: bool,
    tag: Option<FileTag>,
    out: impl Write,
) -> Result<(), OutputError> {
    let channels = if alpha { 4 } else { 3 };
    if rows.len() != width as usize * height as usize * channels {
        return Err(OutputError::Encode(format!(
            "{} bytes are not {width}×{height} pixels of {channels} bytes",
            rows.len()
        )));
    }
    let mut png = PngRows::start(out, width, height, alpha, tag).map_err(OutputError::Encode)?;
    png.rows(rows).map_err(encode_error)?;
    png.finish().map_err(OutputError::Encode)
}

/// The PNG settings kardia writes with: 8-bit RGB or RGBA, the png crate's `Compression::Fast`
/// (its adaptive row filter, then fdeflate) and a text chunk `tag`. [`PngRows`] writes the
/// image data itself, the same bytes as the png crate's `StreamWriter` with these settings.
fn png_header<W: Write>(
    out: W,
    width: u32,
    height: u32,
    alpha: bool,
    tag: Option<FileTag>,
) -> Result<png::Writer<W>, String> {
    if width == 0 || height == 0 {
        return Err(format!("the image is {width}×{height}"));
    }
    let mut encoder = png::Encoder::new(out, width, height);
    if let Some(tag) = tag {
        encoder
            .add_text_chunk(tag.name.into(), tag.text.into())
            .map_err(|e| e.to_string())?;
    }
    encoder.set_color(if alpha {
        png::ColorType::Rgba
    } else {
        png::ColorType::Rgb
    });
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    encoder.write_header().map_err(|e| e.to_string())
}

/// A PNG written row by row, top to bottom: the header by the png crate, each row filtered by
/// [`AdaptiveRowFilter`] (the png crate's adaptive choice) and compressed by fdeflate as the
/// png crate's `StreamWriter` does for `Compression::Fast` (the filter type byte and the
/// filtered row as two pieces of input, which fdeflate's output depends on), in IDAT chunks of
/// 4 KiB like its own. The same bytes as that writer's for every image (tested against it).
struct PngRows<W: Write> {
    deflate: fdeflate::Compressor<IdatChunks<W>>,
    filter: AdaptiveRowFilter,
    /// The last row handed over (zeros before the first): the row above the next one.
    previous: Vec<u8>,
}

impl<W: Write> PngRows<W> {
    /// Writes the signature, the header and the `tag` ([`png_header`]) and readies the rows.
    fn start(
        out: W,
        width: u32,
        height: u32,
        alpha: bool,
        tag: Option<FileTag>,
    ) -> Result<Self, String> {
        let header = png_header(out, width, height, alpha, tag)?;
        let channels = if alpha { 4 } else { 3 };
        let row_len = channels * width as usize;
        let idat = IdatChunks {
            png: header,
            buffer: Vec::with_capacity(IDAT_CHUNK_LEN),
        };
        Ok(PngRows {
            deflate: fdeflate::Compressor::new(idat).map_err(|e| e.to_string())?,
            filter: AdaptiveRowFilter::new(channels, row_len),
            previous: vec![0; row_len],
        })
    }

    /// The bytes of one row.
    fn row_len(&self) -> usize {
        self.previous.len()
    }

    /// Filters and compresses whole rows (`rows.len()` a multiple of [`PngRows::row_len`]),
    /// the next ones down.
    fn rows(&mut self, rows: &[u8]) -> std::io::Result<()> {
        let len = self.row_len();
        let mut above: &[u8] = &self.previous;
        for row in rows.chunks_exact(len) {
            let (kind, filtered) = self.filter.filter(above, row);
            self.deflate.write_data(&[kind])?;
            self.deflate.write_data(filtered)?;
            above = row;
        }
        if rows.len() >= len {
            self.previous.copy_from_slice(&rows[rows.len() - len..]);
        }
        Ok(())
    }

    /// Ends the compressed stream, writes its last IDAT chunk and the IEND chunk, and flushes.
    fn finish(self) -> Result<(), String> {
        let idat = self.deflate.finish().map_err(|e| e.to_string())?;
        let png = idat.finish().map_err(|e| e.to_string())?;
        png.finish().map_err(|e| e.to_string())
    }
}

/// The data length of each IDAT chunk but the last: the png crate's stream writer's default.
const IDAT_CHUNK_LEN: usize = 4 * 1024;

/// The compressed stream cut into IDAT chunks of [`IDAT_CHUNK_LEN`] bytes (the last shorter),
/// written through the png crate's raw-chunk writer.
struct IdatChunks<W: Write> {
    png: png::Writer<W>,
    buffer: Vec<u8>,
}

impl<W: Write> IdatChunks<W> {
    /// Writes what is buffered as the last chunk (none when nothing is) and returns the writer.
    fn finish(mut self) -> Result<png::Writer<W>, png::EncodingError> {
        if !self.buffer.is_empty() {
            self.png.write_chunk(png::chunk::IDAT, &self.buffer)?;
        }
        Ok(self.png)
    }
}

impl<W: Write> Write for IdatChunks<W> {
    fn write(&mut self, data: &[u8]) -> std::io::Result<usize> {
        let taken = data.len().min(IDAT_CHUNK_LEN - self.buffer.len());
        self.buffer.extend_from_slice(&data[..taken]);
        if self.buffer.len() == IDAT_CHUNK_LEN {
            self.png.write_chunk(png::chunk::IDAT, &self.buffer)?;
            self.buffer.clear();
        }
        Ok(taken)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DVec3;

    fn listing_len(dir: &Path) -> usize {
        std::fs::read_dir(dir).unwrap().count()
    }

    /// The PNG the png crate's own `StreamWriter` writes with kardia's settings
    /// ([`png_header`]) from 8-bit rows: what [`PngRows`] must equal byte for byte.
    pub(crate) fn png_crates_own(
        bytes: &[u8],
        width: u32,
        height: u32,
        alpha: bool,
        tag: Option<FileTag>,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        let mut writer = png_header(&mut out, width, height, alpha, tag).unwrap();
        let mut stream = writer.stream_writer().unwrap();
        stream.write_all(bytes).unwrap();
        stream.finish().unwrap();
        writer.finish().unwrap();
        out
    }

    /// [`PngRows`] fed `bytes` in runs of `run` rows, with the filter kernel `scalar` or the
    /// dispatching one.
    fn ours(
        bytes: &[u8],
        (width, height, alpha): (u32, u32, bool),
        tag: Option<FileTag>,
        run: usize,
        scalar: bool,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        let mut png = PngRows::start(&mut out, width, height, alpha, tag).unwrap();
        if scalar {
            png.filter = AdaptiveRowFilter::scalar(if alpha { 4 } else { 3 }, png.row_len());
        }
        for rows in bytes.chunks(run * png.row_len()) {
            png.rows(rows).unwrap();
        }
        png.finish().unwrap();
        out
    }

    #[test]
    fn our_filtered_png_is_the_png_crates_byte_for_byte() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let tag = FileTag {
            name: "kardia-key",
            text: "0123abcd",
        };
        let mut cases = 0;
        for alpha in [false, true] {
            let channels = if alpha { 4 } else { 3 };
            for (width, height) in [
                (1, 1),
                (1, 7),
                (2, 3),
                (11, 5),
                (37, 29),
                (64, 16),
                (133, 9),
            ] {
                // Noise of a few values (equal filter costs are common), full noise, smooth
                // gradients with noise (every filter wins somewhere), a flat image (cost 0),
                // and stretches of each in one image.
                for pattern in 0..5 {
                    let n = (width * height) as usize * channels;
                    let bytes: Vec<u8> = (0..n)
                        .map(|i| {
                            let (x, y) =
                                ((i / channels) as u32 % width, (i / channels) as u32 / width);
                            let smooth = (x * 3 + y * 5 + (i % channels) as u32 * 40) as u8;
                            match pattern {
                                0 => [0, 1, 255][rng.random_range(0..3)],
                                1 => rng.random(),
                                2 => smooth.wrapping_add(rng.random_range(0..3)),
                                3 => 77,
                                _ => match (x / 8 + y) % 3 {
                                    0 => smooth,
                                    1 => rng.random(),
                                    _ => 0,
                                },
                            }
                        })
                        .collect();
                    let shape = (width, height, alpha);
                    for tag in [None, Some(tag)] {
                        let want = png_crates_own(&bytes, width, height, alpha, tag);
                        for (run, scalar) in [(1, false), (3, false), (16, false), (5, true)] {
                            let got = ours(&bytes, shape, tag, run, scalar);
                            assert!(
                                got == want,
                                "{width}×{height} alpha {alpha} pattern {pattern} run {run} \
                                 scalar {scalar}: {} bytes against png's {}",
                                got.len(),
                                want.len()
                            );
                            cases += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(cases, 2 * 7 * 5 * 2 * 4);
    }

    #[test]
    fn the_srgb8_entry_writes_the_same_bytes_and_checks_the_length() {
        let bytes: Vec<u8> = (0..5 * 4 * 4).map(|i| (i * 37 % 251) as u8).collect();
        let mut out = Vec::new();
        encode_png_srgb8(&bytes, 5, 4, true, None, &mut out).unwrap();
        assert!(out == png_crates_own(&bytes, 5, 4, true, None));
        assert!(encode_png_srgb8(&bytes, 5, 4, false, None, Vec::new()).is_err());
        assert!(encode_png_srgb8(&[], 0, 4, false, None, Vec::new()).is_err());
    }

    #[test]
    fn a_large_image_fills_several_idat_chunks_as_png_does() {
        // 300×200 RGB of noise: about 180 KB compressed, 44 chunks of 4 KiB and a short one.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let bytes: Vec<u8> = (0..300 * 200 * 3).map(|_| rng.random()).collect();
        let want = png_crates_own(&bytes, 300, 200, false, None);
        assert!(want.len() > 10 * IDAT_CHUNK_LEN);
        for scalar in [false, true] {
            assert!(ours(&bytes, (300, 200, false), None, 16, scalar) == want);
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
        assert_eq!(listing_len(dir.path()), 3);
    }

    #[test]
    fn alpha_round_trips_through_png_and_exr() {
        // Premultiplied (0.25, 0.1, 0) at coverage 0.5 is the straight colour (0.5, 0.2, 0).
        let mut img = Image::transparent(3, 1);
        img.set(0, 0, DVec3::new(0.25, 0.1, 0.0));
        img.set_alpha(0, 0, 0.5);
        img.set(1, 0, DVec3::new(1.0, 0.5, 0.0));
        img.set_alpha(1, 0, 1.0);
        let mut png = Vec::new();
        encode_png(&img, &mut png).unwrap();
        let decoded = image::load_from_memory(&png).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgba8);
        let decoded = decoded.to_rgba8();
        let straight = [
            crate::film::linear_to_srgb8(0.5),
            crate::film::linear_to_srgb8(0.2),
            0,
            128,
        ];
        assert_eq!(decoded.get_pixel(0, 0).0, straight);
        assert_eq!(decoded.get_pixel(1, 0).0, [255, 188, 0, 255]);
        assert_eq!(
            decoded.get_pixel(2, 0).0,
            [0, 0, 0, 0],
            "uncovered: transparent"
        );
        for half in [false, true] {
            let mut exr = std::io::Cursor::new(Vec::new());
            encode_exr(&img, half, &mut exr).unwrap();
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("a.exr");
            std::fs::write(&path, exr.into_inner()).unwrap();
            let read = exr::prelude::read_first_rgba_layer_from_file(
                &path,
                |res, _| vec![(0.0f32, 0.0f32, 0.0f32, 0.0f32); res.width() * res.height()],
                |v, pos, px: (f32, f32, f32, f32)| v[pos.x()] = px,
            )
            .unwrap();
            let px = &read.layer_data.channel_data.pixels;
            let tolerance = if half { 1e-3 } else { 0.0 };
            let (r, g, b, a) = px[0];
            assert!((r - 0.25).abs() <= tolerance && (g - 0.1).abs() <= tolerance);
            assert_eq!((b, a), (0.0, 0.5), "premultiplied colour, coverage in A");
            assert_eq!(px[2], (0.0, 0.0, 0.0, 0.0));
        }
        // Without alpha nothing changes: an RGB PNG.
        let mut opaque = Vec::new();
        encode_png(&Image::new(2, 2), &mut opaque).unwrap();
        let decoded = image::load_from_memory(&opaque).unwrap();
        assert_eq!(decoded.color(), image::ColorType::Rgb8);
    }

    #[test]
    fn encoders_write_to_memory() {
        let mut img = Image::new(2, 2);
        img.set(0, 0, DVec3::new(1e9, 0.5, -1.0));
        let mut png = Vec::new();
        encode_png(&img, &mut png).unwrap();
        let decoded = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(decoded.get_pixel(0, 0).0, [255, 188, 0]);
        let mut exr = std::io::Cursor::new(Vec::new());
        encode_exr(&img, true, &mut exr).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.exr");
        std::fs::write(&path, exr.into_inner()).unwrap();
        let image = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| vec![(0.0f32, 0.0f32, 0.0f32); res.width() * res.height()],
            |v, pos, (r, g, b, _a): (f32, f32, f32, f32)| v[pos.y() * 2 + pos.x()] = (r, g, b),
        )
        .unwrap();
        let first = image.layer_data.channel_data.pixels[0];
        assert_eq!(
            first,
            (65504.0, 0.5, -1.0),
            "half channels saturate, finite"
        );
        assert!(encode_png(&Image::new(0, 3), Vec::new()).is_err());
    }

    #[test]
    fn streamed_png_has_the_same_pixels_whatever_the_order_of_rows() {
        for alpha in [false, true] {
            let dir = tempfile::tempdir().unwrap();
            let (w, h) = (37u32, 29u32);
            let mut img = Image::new(w, h);
            for y in 0..h {
                for x in 0..w {
                    let v =
                        DVec3::new(x as f64 / 36.0, y as f64 / 28.0, ((x * y) % 7) as f64 / 5.0);
                    img.set(x, y, v);
                    if alpha {
                        img.set_alpha(x, y, ((x + y) % 5) as f64 / 4.0);
                    }
                }
            }
            let whole = dir.path().join("whole.png");
            write_image(&img, &whole).unwrap();
            let streamed = dir.path().join("streamed.png");
            let rows = |y0: u32, y1: u32| {
                let range = (y0 * w) as usize..(y1 * w) as usize;
                let alpha = img.alpha.as_ref().map(|a| &a[range.clone()]);
                (&img.pixels[range], alpha)
            };
            let mut file = AtomicFile::create(&streamed).unwrap();
            let (answer, written) = encode_png_streaming(&mut file, w, h, alpha, |sink| {
                // Bottom runs first, from two threads, in runs of uneven size.
                std::thread::scope(|s| {
                    s.spawn(|| {
                        let (p, a) = rows(20, h);
                        sink.rows(20, p, a);
                        let (p, a) = rows(10, 20);
                        sink.rows(10, p, a);
                    });
                    s.spawn(|| {
                        for y in (0..10).rev() {
                            let (p, a) = rows(y, y + 1);
                            sink.rows(y, p, a);
                        }
                    });
                });
                42
            });
            written.unwrap();
            file.commit().unwrap();
            assert_eq!(answer, 42);
            let a = image::open(&whole).unwrap();
            let b = image::open(&streamed).unwrap();
            assert_eq!(a.color().has_alpha(), alpha);
            assert_eq!(b.color().has_alpha(), alpha);
            assert_eq!(a.to_rgba8(), b.to_rgba8());
            assert_eq!(listing_len(dir.path()), 2, "a temporary file was left");
        }
    }

    #[test]
    fn only_the_run_the_encoder_waits_for_wakes_it() {
        let queue = std::sync::Arc::new(RowQueue::default());
        let runs = RunsInOrder(queue.clone());
        // Bands finishing out of order (two render threads): the encoder, waiting for row 0,
        // is woken by row 0's run alone, and then takes both.
        assert!(!queue.push(16, vec![1; 3]));
        assert!(queue.push(0, vec![0; 3]));
        let (batch, closed) = runs.next_batch(0);
        assert_eq!(batch.iter().map(|run| run.0).collect::<Vec<_>>(), [16, 0]);
        assert!(!closed);
        // Now waiting for row 32 (it returns at once when that run is already there).
        let waiter = std::thread::spawn(move || {
            let batch = runs.next_batch(32);
            (batch, runs)
        });
        while queue.lock().wanted != 32 {
            std::thread::yield_now();
        }
        assert!(!queue.push(48, vec![3; 3]));
        assert!(queue.push(32, vec![2; 3]));
        let ((batch, closed), runs) = waiter.join().unwrap();
        assert_eq!(batch.iter().map(|run| run.0).collect::<Vec<_>>(), [48, 32]);
        assert!(!closed);
        drop(runs); // the encoder stopped: later rows are dropped
        assert!(!queue.push(64, vec![4; 3]));
        assert!(queue.lock().runs.is_empty());
    }

    #[test]
    fn a_producer_that_panics_does_not_leave_the_encoder_waiting() {
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let img = Image::new(4, 3);
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                encode_png_streaming(Vec::new(), 4, 3, false, |sink| {
                    sink.rows(1, &img.pixels[4..8], None); // not the row the encoder waits for
                    panic!("the render failed");
                })
            }));
            let _ = done.send(result.is_err());
        });
        let panicked = finished
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("the encoder thread was left waiting for rows");
        assert!(panicked);
    }

    #[test]
    fn streamed_png_with_missing_or_repeated_rows_fails() {
        let img = Image::new(4, 3);
        let (_, missing) = encode_png_streaming(Vec::new(), 4, 3, false, |sink| {
            sink.rows(0, &img.pixels[..8], None)
        });
        assert!(missing.is_err());
        let (_, twice) = encode_png_streaming(Vec::new(), 4, 3, true, |sink| {
            sink.rows(0, &img.pixels, None);
            sink.rows(1, &img.pixels[4..8], None);
        });
        assert!(twice.is_err());
        let (_, empty) = encode_png_streaming(Vec::new(), 0, 3, false, |_| ());
        assert!(empty.is_err());
    }

    #[test]
    fn exr_bytes_do_not_depend_on_the_order_blocks_finish_in() {
        // 512×384: 48 blocks of 64×64, compressed on many threads.
        let (w, h) = (512u32, 384u32);
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let v = DVec3::new(
                    (x as f64 * 0.37).sin(),
                    ((x * y) % 97) as f64 / 13.0,
                    y as f64 / 7.0,
                );
                img.set(x, y, v);
            }
        }
        for half in [false, true] {
            let encoded = || {
                let mut out = std::io::Cursor::new(Vec::new());
                encode_exr(&img, half, &mut out).unwrap();
                out.into_inner()
            };
            let first = encoded();
            for _ in 0..6 {
                assert!(first == encoded(), "half {half}: the bytes changed");
            }
        }
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
            alpha: None,
        };
        assert!(write_image(&bad, &target).is_err());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(listing_len(dir.path()), 1);
    }
}
