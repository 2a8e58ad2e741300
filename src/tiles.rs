//! Parts of one image rendered apart — row bands (`--tile I/N`) or rectangles (`--region`) —
//! each written to a file of its own that says what it is part of (PNG text chunk, OpenEXR
//! attribute), and [`assemble`], which joins them into the file a single render would have
//! written, byte for byte, refusing parts that do not fit together.

use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use crate::film::{self, AtomicFile, Image, ImageFormat, OutputError, Region};
use crate::integrator::TILE_SIZE;

/// Name of the PNG text chunk and of the OpenEXR attribute holding a part's [`PartInfo`].
pub const METADATA_KEY: &str = "kardia-part";

/// Name of the PNG text chunk and of the OpenEXR attribute holding a whole image's render key
/// ([`render_key`]): what `--resume` compares, and what `assemble` writes into a joined file.
pub const KEY_TAG: &str = "kardia-key";

/// What a part file is part of. Parts join only when everything but `region` is equal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartInfo {
    /// Width of the whole image, pixels.
    pub full_width: u32,
    /// Height of the whole image, pixels.
    pub full_height: u32,
    /// Where this part lies in the whole image.
    pub region: Region,
    /// The sample seed the part was rendered with (the frame's seed in a sequence).
    pub seed: u64,
    /// Samples per pixel.
    pub spp: u32,
    /// The frame number (0 for a still).
    pub frame: u32,
    /// SHA-256 (hex) of the scene text and every setting that changes pixels: parts of
    /// different scenes or settings never join.
    pub key: String,
}

impl PartInfo {
    /// The one-line text stored in the file.
    pub fn to_text(&self) -> String {
        let r = self.region;
        format!(
            "kardia-part 1 full={}x{} region={},{},{},{} seed={} spp={} frame={} key={}",
            self.full_width,
            self.full_height,
            r.x,
            r.y,
            r.width,
            r.height,
            self.seed,
            self.spp,
            self.frame,
            self.key
        )
    }

    /// Reads [`PartInfo::to_text`]'s line back.
    pub fn from_text(text: &str) -> Option<Self> {
        let mut fields = text.split_whitespace();
        if fields.next()? != "kardia-part" || fields.next()? != "1" {
            return None;
        }
        let mut get = |name: &str| {
            fields
                .next()?
                .strip_prefix(name)?
                .strip_prefix('=')
                .map(str::to_string)
        };
        let full = get("full")?;
        let (w, h) = full.split_once('x')?;
        let region: Vec<u32> = get("region")?
            .split(',')
            .map(|v| v.parse().ok())
            .collect::<Option<_>>()?;
        let [x, y, width, height] = region[..] else {
            return None;
        };
        Some(Self {
            full_width: w.parse().ok()?,
            full_height: h.parse().ok()?,
            region: Region {
                x,
                y,
                width,
                height,
            },
            seed: get("seed")?.parse().ok()?,
            spp: get("spp")?.parse().ok()?,
            frame: get("frame")?.parse().ok()?,
            key: get("key")?,
        })
    }
}

/// SHA-256 (hex) of a scene text and a description of the settings (any text that names
/// every setting that changes pixels).
pub fn render_key(scene_text: &str, settings: &str) -> String {
    let mut hash = Sha256::new();
    hash.update(b"kardia render key 1\n");
    hash.update((scene_text.len() as u64).to_le_bytes());
    hash.update(scene_text.as_bytes());
    hash.update(settings.as_bytes());
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Row band `index` (from 0) of `count` of a `width × height` image: rows
/// `⌊index·height/count⌋ .. ⌊(index+1)·height/count⌋`, so the bands cover the image exactly.
/// An error when `index ≥ count` or a band would be empty (`count > height`).
pub fn band(index: u32, count: u32, width: u32, height: u32) -> Result<Region, String> {
    if count == 0 || index >= count {
        return Err(format!(
            "tile {index}/{count}: the index must be from 0 to {}",
            count.saturating_sub(1)
        ));
    }
    if count > height {
        return Err(format!(
            "{count} row bands do not fit in an image {height} pixels tall"
        ));
    }
    let edge = |i: u32| (u64::from(i) * u64::from(height) / u64::from(count)) as u32;
    let (top, bottom) = (edge(index), edge(index + 1));
    Ok(Region {
        x: 0,
        y: top,
        width,
        height: bottom - top,
    })
}

/// Writes a part atomically: `image` (the region's pixels) in `format` with `info` in a PNG
/// text chunk or an OpenEXR attribute named [`METADATA_KEY`].
pub fn write_part(
    image: &Image,
    info: &PartInfo,
    format: ImageFormat,
    path: &Path,
) -> Result<(), OutputError> {
    let mut file = AtomicFile::create(path)?;
    match format {
        ImageFormat::Png => {
            let mut encoder = png::Encoder::new(&mut file, image.width, image.height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder
                .add_text_chunk(METADATA_KEY.into(), info.to_text())
                .map_err(encode_error)?;
            let mut writer = encoder.write_header().map_err(encode_error)?;
            writer
                .write_image_data(&image.to_srgb8())
                .map_err(encode_error)?;
            writer.finish().map_err(encode_error)?;
        }
        ImageFormat::ExrFloat | ImageFormat::ExrHalf => {
            write_exr_part(image, info, format == ImageFormat::ExrHalf, &mut file)?;
        }
    }
    file.commit()
}

fn encode_error(e: impl std::fmt::Display) -> OutputError {
    OutputError::Encode(e.to_string())
}

fn write_exr_part(
    image: &Image,
    info: &PartInfo,
    half: bool,
    out: impl Write + Seek + Send,
) -> Result<(), OutputError> {
    let text = info.to_text();
    let tag = film::FileTag {
        name: METADATA_KEY,
        text: &text,
    };
    film::encode_exr_tagged(image, half, Some(tag), out)
}

/// Why parts could not be joined.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum AssembleError {
    /// No parts given.
    #[error("no parts to assemble")]
    NoParts,
    /// A part could not be read or decoded.
    #[error("cannot read the part {path}: {reason}")]
    Unreadable {
        /// The part.
        path: String,
        /// Why.
        reason: String,
    },
    /// A file without kardia part metadata.
    #[error("{0} is not a kardia part (it has no `kardia-part` metadata): render parts with --tile I/N or --region")]
    NotAPart(String),
    /// Two parts of different images (size, seed, samples, frame, scene or settings).
    #[error("{a} and {b} are parts of different images: their {what} differ ({va} against {vb})")]
    Mismatch {
        /// One part.
        a: String,
        /// Another part.
        b: String,
        /// What differs.
        what: &'static str,
        /// Its value in `a`.
        va: String,
        /// Its value in `b`.
        vb: String,
    },
    /// Parts of PNG and EXR mixed, or an output of another format.
    #[error("{0}")]
    Format(String),
    /// A part's pixels are not the size its metadata says, or it lies outside the image.
    #[error("{path} holds {width}×{height} pixels, but its metadata says region {region}")]
    BadPart {
        /// The part.
        path: String,
        /// Its pixel width.
        width: u32,
        /// Its pixel height.
        height: u32,
        /// What the metadata says.
        region: String,
    },
    /// Two parts cover the same pixel.
    #[error("{a} and {b} overlap (both hold pixel ({x}, {y})): assemble refuses to choose")]
    Overlap {
        /// One part.
        a: String,
        /// Another part.
        b: String,
        /// A pixel both hold.
        x: u32,
        /// A pixel both hold.
        y: u32,
    },
    /// Pixels no part covers.
    #[error("the parts do not cover the {width}×{height} image: nothing holds the pixels in x {x0}..={x1}, y {y0}..={y1} ({count} pixels); is a part missing?")]
    Missing {
        /// Full width.
        width: u32,
        /// Full height.
        height: u32,
        /// Bounding box of the uncovered pixels.
        x0: u32,
        /// Bounding box of the uncovered pixels.
        x1: u32,
        /// Bounding box of the uncovered pixels.
        y0: u32,
        /// Bounding box of the uncovered pixels.
        y1: u32,
        /// How many pixels are uncovered.
        count: u64,
    },
    /// The output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// A part read back: its metadata and pixels (8-bit sRGB bytes for PNG, linear for EXR).
struct Part {
    path: String,
    info: PartInfo,
    pixels: Pixels,
}

enum Pixels {
    Srgb8(Vec<u8>),
    Linear(Image),
}

fn unreadable(path: &Path, reason: impl std::fmt::Display) -> AssembleError {
    AssembleError::Unreadable {
        path: path.display().to_string(),
        reason: reason.to_string(),
    }
}

fn read_png_part(path: &Path) -> Result<Part, AssembleError> {
    let file = std::fs::File::open(path).map_err(|e| unreadable(path, e))?;
    let decoder = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = decoder.read_info().map_err(|e| unreadable(path, e))?;
    let mut bytes = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let frame = reader
        .next_frame(&mut bytes)
        .map_err(|e| unreadable(path, e))?;
    if frame.color_type != png::ColorType::Rgb || frame.bit_depth != png::BitDepth::Eight {
        return Err(AssembleError::NotAPart(path.display().to_string()));
    }
    bytes.truncate(frame.buffer_size());
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .find(|t| t.keyword == METADATA_KEY)
        .map(|t| t.text.clone());
    let info = text
        .as_deref()
        .and_then(PartInfo::from_text)
        .ok_or_else(|| AssembleError::NotAPart(path.display().to_string()))?;
    check_pixel_size(path, &info, frame.width, frame.height)?;
    Ok(Part {
        path: path.display().to_string(),
        info,
        pixels: Pixels::Srgb8(bytes),
    })
}

fn read_exr_part(path: &Path) -> Result<(Part, bool), AssembleError> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, channels: &RgbChannels| {
                let half = channels.0.sample_type == SampleType::F16;
                (
                    film::Image::new(size.width() as u32, size.height() as u32),
                    half,
                )
            },
            |(img, _): &mut (film::Image, bool), pos, (r, g, b): (f32, f32, f32)| {
                let w = img.width as usize;
                img.pixels[pos.y() * w + pos.x()] = film::Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| unreadable(path, e))?;
    // A custom header attribute may be read back as the image's or as the layer's.
    let key = Text::from(METADATA_KEY);
    let found = image
        .attributes
        .other
        .get(&key)
        .or_else(|| image.layer_data.attributes.other.get(&key));
    let text = match found {
        Some(AttributeValue::Text(t)) => Some(t.to_string()),
        _ => None,
    };
    let info = text
        .as_deref()
        .and_then(PartInfo::from_text)
        .ok_or_else(|| AssembleError::NotAPart(path.display().to_string()))?;
    let (pixels, half) = image.layer_data.channel_data.pixels;
    check_pixel_size(path, &info, pixels.width, pixels.height)?;
    Ok((
        Part {
            path: path.display().to_string(),
            info,
            pixels: Pixels::Linear(pixels),
        },
        half,
    ))
}

fn check_pixel_size(path: &Path, info: &PartInfo, w: u32, h: u32) -> Result<(), AssembleError> {
    let r = info.region;
    if (w, h) != (r.width, r.height) || !r.fits(info.full_width, info.full_height) {
        return Err(AssembleError::BadPart {
            path: path.display().to_string(),
            width: w,
            height: h,
            region: format!(
                "{}×{} at ({}, {}) of {}×{}",
                r.width, r.height, r.x, r.y, info.full_width, info.full_height
            ),
        });
    }
    Ok(())
}

/// Joins part files (PNG parts into a PNG, EXR parts into an EXR of the parts' sample type)
/// into `output`, atomically: the file `kardia render` writes for the whole image with the
/// same scene and settings, byte for byte. Every part must carry [`PartInfo`] of the same
/// image; together they must cover it exactly once.
pub fn assemble(parts: &[PathBuf], output: &Path) -> Result<(), AssembleError> {
    let format = ImageFormat::from_path(output)?;
    if parts.is_empty() {
        return Err(AssembleError::NoParts);
    }
    let mut read = Vec::new();
    let mut halves = Vec::new();
    for path in parts {
        let part_format = ImageFormat::from_path(path).map_err(|e| unreadable(path, e))?;
        match (format, part_format) {
            (ImageFormat::Png, ImageFormat::Png) => read.push(read_png_part(path)?),
            (ImageFormat::Png, _) | (_, ImageFormat::Png) => {
                return Err(AssembleError::Format(format!(
                    "{} and the output {} are of different formats: PNG parts join into a \
                     .png, EXR parts into an .exr",
                    path.display(),
                    output.display()
                )))
            }
            _ => {
                let (part, half) = read_exr_part(path)?;
                read.push(part);
                halves.push(half);
            }
        }
    }
    let first = &read[0];
    for part in &read[1..] {
        let (a, b) = (&first.info, &part.info);
        let differ = |what, va: String, vb: String| {
            (va != vb).then(|| AssembleError::Mismatch {
                a: first.path.clone(),
                b: part.path.clone(),
                what,
                va,
                vb,
            })
        };
        // The frame first: a frame's seed derives from it, so parts of two frames differ in
        // their seeds too, and "frames" is the answer.
        let checks = [
            differ("frames", a.frame.to_string(), b.frame.to_string()),
            differ(
                "image sizes",
                format!("{}×{}", a.full_width, a.full_height),
                format!("{}×{}", b.full_width, b.full_height),
            ),
            differ("samples per pixel", a.spp.to_string(), b.spp.to_string()),
            differ("seeds", a.seed.to_string(), b.seed.to_string()),
            differ(
                "scenes or settings (render keys)",
                a.key[..12.min(a.key.len())].to_string() + "…",
                b.key[..12.min(b.key.len())].to_string() + "…",
            ),
        ];
        if let Some(e) = checks.into_iter().flatten().next() {
            return Err(e);
        }
    }
    if halves.iter().any(|&h| h != halves[0]) {
        return Err(AssembleError::Format(
            "the EXR parts mix 16-bit half and 32-bit float channels".into(),
        ));
    }
    let (w, h) = (first.info.full_width, first.info.full_height);
    check_coverage(&read, w, h)?;
    // The joined file carries the render key, as the single render does.
    let key_tag = Some(film::FileTag {
        name: KEY_TAG,
        text: &first.info.key,
    });
    let mut file = AtomicFile::create(output)?;
    match format {
        ImageFormat::Png => {
            let mut rgb = vec![0u8; 3 * w as usize * h as usize];
            for part in &read {
                let Pixels::Srgb8(bytes) = &part.pixels else {
                    unreachable!("PNG parts hold bytes")
                };
                let r = part.info.region;
                let row = 3 * r.width as usize;
                for (k, src) in bytes.chunks_exact(row).enumerate() {
                    let start = 3 * ((r.y as usize + k) * w as usize + r.x as usize);
                    rgb[start..start + row].copy_from_slice(src);
                }
            }
            encode_png_like_render(&rgb, w, h, key_tag, &mut file)?;
        }
        _ => {
            let mut image = Image::new(w, h);
            for part in &read {
                let Pixels::Linear(tile) = &part.pixels else {
                    unreachable!("EXR parts hold floats")
                };
                image.paste(part.info.region.x, part.info.region.y, tile);
            }
            let half = halves[0];
            film::encode_exr_tagged(&image, half, key_tag, &mut file)?;
        }
    }
    file.commit()?;
    Ok(())
}

/// Fails unless the parts' regions cover the `w × h` image exactly once.
fn check_coverage(parts: &[Part], w: u32, h: u32) -> Result<(), AssembleError> {
    let mut owner: Vec<u32> = vec![u32::MAX; w as usize * h as usize];
    for (k, part) in parts.iter().enumerate() {
        let r = part.info.region;
        for y in r.y..r.y + r.height {
            for x in r.x..r.x + r.width {
                let slot = &mut owner[y as usize * w as usize + x as usize];
                if *slot != u32::MAX {
                    return Err(AssembleError::Overlap {
                        a: parts[*slot as usize].path.clone(),
                        b: part.path.clone(),
                        x,
                        y,
                    });
                }
                *slot = k as u32;
            }
        }
    }
    let (mut x0, mut x1, mut y0, mut y1, mut count) = (u32::MAX, 0, u32::MAX, 0, 0u64);
    for (i, &o) in owner.iter().enumerate() {
        if o == u32::MAX {
            let (x, y) = ((i % w as usize) as u32, (i / w as usize) as u32);
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            count += 1;
        }
    }
    if count > 0 {
        return Err(AssembleError::Missing {
            width: w,
            height: h,
            x0,
            x1,
            y0,
            y1,
            count,
        });
    }
    Ok(())
}

/// Encodes 8-bit sRGB rows as `kardia render` encodes a whole PNG (the same streaming encoder
/// with the same `tag`, fed the same bands of [`TILE_SIZE`] rows), so the bytes are the same. Each byte goes
/// through its exact linear value, which converts back to the same byte.
fn encode_png_like_render(
    rgb: &[u8],
    w: u32,
    h: u32,
    tag: Option<film::FileTag>,
    out: impl Write + Send,
) -> Result<(), OutputError> {
    let linear: Vec<f32> = (0..=255u8)
        .map(|c| film::srgb8_to_linear(c) as f32)
        .collect();
    let row_bytes = 3 * w as usize;
    let ((), written) = film::encode_png_streaming_tagged(out, w, h, false, tag, |sink| {
        for (band, rows) in rgb.chunks(row_bytes * TILE_SIZE as usize).enumerate() {
            let pixels: Vec<film::Vec3> = rows
                .chunks_exact(3)
                .map(|p| {
                    film::Vec3::new(
                        linear[p[0] as usize],
                        linear[p[1] as usize],
                        linear[p[2] as usize],
                    )
                })
                .collect();
            sink.rows(band as u32 * TILE_SIZE, &pixels, None);
        }
    });
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_the_image_exactly() {
        for (count, height) in [(1, 7), (3, 10), (4, 480), (7, 7)] {
            let mut next = 0;
            for i in 0..count {
                let r = band(i, count, 5, height).unwrap();
                assert_eq!((r.x, r.y, r.width), (0, next, 5));
                assert!(r.height >= 1);
                next = r.y + r.height;
            }
            assert_eq!(next, height);
        }
        assert!(band(4, 4, 5, 10).is_err());
        assert!(band(0, 11, 5, 10).is_err());
        assert!(band(0, 0, 5, 10).is_err());
    }

    #[test]
    fn part_info_round_trips() {
        let info = PartInfo {
            full_width: 640,
            full_height: 480,
            region: Region {
                x: 0,
                y: 120,
                width: 640,
                height: 120,
            },
            seed: u64::MAX,
            spp: 16,
            frame: 7,
            key: render_key("CAMERA …", "spp=16"),
        };
        assert_eq!(PartInfo::from_text(&info.to_text()), Some(info.clone()));
        assert_eq!(info.key.len(), 64);
        assert_ne!(info.key, render_key("CAMERA …", "spp=17"));
        assert_eq!(PartInfo::from_text("kardia-part 2 full=1x1"), None);
        assert_eq!(PartInfo::from_text("something else"), None);
    }

    #[test]
    fn every_byte_survives_the_trip_through_linear() {
        let mut image = Image::new(256, 1);
        for c in 0..=255u8 {
            let v = film::srgb8_to_linear(c) as f32;
            image.pixels[c as usize] = film::Vec3::new(v, v, v);
        }
        let bytes = image.to_srgb8();
        for c in 0..=255u8 {
            assert_eq!(bytes[3 * c as usize], c, "code {c}");
        }
    }
}
