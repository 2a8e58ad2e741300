//! Animated outputs: every frame of a sequence in one file, GIF or APNG, looping forever.
//! Frames are encoded as they are handed over (8-bit sRGB, as a PNG still would store them).
//! Each file carries the animation's render key (a comment in a GIF, a text chunk in an APNG),
//! so that `--resume` keeps only an animation made with the same scene and settings.

use std::io::{Read, Write};
use std::path::Path;

use crate::film::{Image, OutputError};

/// The animated file formats, chosen by the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnimatedFormat {
    /// GIF (`.gif`): 256 colours a frame (NeuQuant quantisation), delays in 1/100 s.
    Gif,
    /// Animated PNG (`.apng`): full 8-bit RGB frames (RGBA with straight alpha for frames
    /// with alpha), lossless.
    Apng,
}

impl AnimatedFormat {
    /// The animated format `path` asks for by its extension (case-insensitive), if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "gif" => Some(Self::Gif),
            "apng" => Some(Self::Apng),
            _ => None,
        }
    }
}

/// An animated file being written: [`AnimatedEncoder::add_frame`] once per frame, in order,
/// then [`AnimatedEncoder::finish`].
pub struct AnimatedEncoder<W: Write> {
    inner: Inner<W>,
    width: u32,
    height: u32,
    /// Whether frames are stored with alpha (APNG only).
    alpha: bool,
}

enum Inner<W: Write> {
    /// The GIF encoder and each frame's delay in 1/100 s.
    Gif(Box<gif::Encoder<W>>, u16),
    Apng(png::Writer<W>),
}

/// GIF's comment extension label.
const GIF_COMMENT: u8 = 0xFE;

/// The GIF frame delay for `fps`, in 1/100 s: 1000/fps milliseconds, each cut to a whole
/// number, as the image crate's encoder did (a 24 fps GIF shows each frame 4/100 s).
fn gif_delay(fps: f64) -> u16 {
    let milliseconds = 1000 / (fps.round().max(1.0) as u32);
    (milliseconds / 10) as u16
}

fn encode_error(e: impl std::fmt::Display) -> OutputError {
    OutputError::Encode(e.to_string())
}

/// The APNG frame delay for `fps` as `numerator / denominator` seconds.
fn apng_delay(fps: f64) -> (u16, u16) {
    if fps.fract() == 0.0 && (1.0..=65535.0).contains(&fps) {
        (1, fps as u16)
    } else {
        ((1000.0 / fps).round().clamp(1.0, 65535.0) as u16, 1000)
    }
}

impl<W: Write> AnimatedEncoder<W> {
    /// Starts an animation of `frames` frames of `width × height` pixels shown at `fps` frames
    /// per second into `out`, carrying `key` (the animation's render key, read back by
    /// [`read_key`]); with `alpha`, an APNG of RGBA frames with straight alpha (a GIF refuses
    /// it: its transparency is only on or off).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        format: AnimatedFormat,
        out: W,
        width: u32,
        height: u32,
        frames: u32,
        fps: f64,
        alpha: bool,
        key: &str,
    ) -> Result<Self, OutputError> {
        if alpha && format == AnimatedFormat::Gif {
            return Err(OutputError::Encode(
                "a GIF cannot hold partial transparency: use an APNG for alpha".into(),
            ));
        }
        let inner = match format {
            AnimatedFormat::Gif => {
                let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
                    return Err(OutputError::Encode(format!(
                        "a GIF holds at most 65535×65535 pixels, not {width}×{height}"
                    )));
                };
                let mut encoder = gif::Encoder::new(out, w, h, &[]).map_err(encode_error)?;
                encoder
                    .set_repeat(gif::Repeat::Infinite)
                    .map_err(encode_error)?;
                encoder
                    .write_raw_extension(
                        gif::AnyExtension(GIF_COMMENT),
                        &[format!("{}={key}", crate::tiles::KEY_TAG).as_bytes()],
                    )
                    .map_err(encode_error)?;
                Inner::Gif(Box::new(encoder), gif_delay(fps))
            }
            AnimatedFormat::Apng => {
                let mut encoder = png::Encoder::new(out, width, height);
                encoder.set_color(if alpha {
                    png::ColorType::Rgba
                } else {
                    png::ColorType::Rgb
                });
                encoder.set_depth(png::BitDepth::Eight);
                encoder
                    .add_text_chunk(crate::tiles::KEY_TAG.into(), key.into())
                    .map_err(encode_error)?;
                encoder.set_animated(frames, 0).map_err(encode_error)?;
                let (num, den) = apng_delay(fps);
                encoder.set_frame_delay(num, den).map_err(encode_error)?;
                Inner::Apng(encoder.write_header().map_err(encode_error)?)
            }
        };
        Ok(Self {
            inner,
            width,
            height,
            alpha,
        })
    }

    /// Adds the next frame (its size must be the animation's; in an animation with alpha, a
    /// frame without alpha is stored opaque).
    pub fn add_frame(&mut self, image: &Image) -> Result<(), OutputError> {
        if (image.width, image.height) != (self.width, self.height) {
            return Err(OutputError::Encode(format!(
                "a {}×{} frame in a {}×{} animation",
                image.width, image.height, self.width, self.height
            )));
        }
        if self.alpha {
            let rgba = image.to_srgba8();
            return match &mut self.inner {
                Inner::Apng(writer) => writer.write_image_data(&rgba).map_err(encode_error),
                Inner::Gif(..) => Err(encode_error("a GIF cannot hold alpha")),
            };
        }
        let rgb = image.to_srgb8();
        match &mut self.inner {
            Inner::Gif(encoder, delay) => {
                let mut rgba: Vec<u8> = rgb
                    .chunks_exact(3)
                    .flat_map(|p| [p[0], p[1], p[2], 255])
                    .collect();
                // The sizes fit in u16: checked when the encoder was made.
                let mut frame = gif::Frame::from_rgba_speed(
                    self.width as u16,
                    self.height as u16,
                    &mut rgba,
                    10,
                );
                frame.delay = *delay;
                frame.dispose = gif::DisposalMethod::Background;
                encoder.write_frame(&frame).map_err(encode_error)
            }
            Inner::Apng(writer) => writer.write_image_data(&rgb).map_err(encode_error),
        }
    }

    /// Ends the file (every frame must have been added).
    pub fn finish(self) -> Result<(), OutputError> {
        match self.inner {
            Inner::Gif(encoder, _) => encoder.into_inner().map(drop).map_err(encode_error),
            Inner::Apng(writer) => writer.finish().map_err(encode_error),
        }
    }
}

/// The render key an animated file carries (see [`AnimatedEncoder::new`]), if it is a GIF or
/// APNG that holds one; `None` for anything else, a damaged file included.
pub fn read_key(path: &Path) -> Option<String> {
    let file = std::io::BufReader::new(std::fs::File::open(path).ok()?);
    match AnimatedFormat::from_path(path)? {
        AnimatedFormat::Gif => {
            // The key is written before the first frame, within the file's first bytes
            // (header, screen descriptor, loop extension, the comment): no need to read the
            // frames.
            let mut head = Vec::new();
            file.take(GIF_KEY_WITHIN).read_to_end(&mut head).ok()?;
            let prefix = format!("{}=", crate::tiles::KEY_TAG);
            gif_comments(&head)?
                .into_iter()
                .find_map(|c| c.strip_prefix(prefix.as_bytes()).map(<[u8]>::to_vec))
                .and_then(|k| String::from_utf8(k).ok())
        }
        AnimatedFormat::Apng => crate::film::read_png_tag(file, crate::tiles::KEY_TAG),
    }
}

/// How far into a GIF [`read_key`] looks for the key: past the largest global colour table
/// (768 bytes) and the loop extension, with room for a key of any length kardia writes.
const GIF_KEY_WITHIN: u64 = 64 * 1024;

/// The comment extensions of a GIF that come before its first image (where
/// [`AnimatedEncoder`] writes the key), each with its sub-blocks joined; `None` when the
/// bytes end or break before that point.
fn gif_comments(bytes: &[u8]) -> Option<Vec<Vec<u8>>> {
    if !bytes.starts_with(b"GIF89a") && !bytes.starts_with(b"GIF87a") {
        return None;
    }
    let flags = *bytes.get(10)?;
    let mut at = 13;
    if flags & 0x80 != 0 {
        at += 3 << ((flags & 7) + 1); // the global colour table
    }
    let mut comments = Vec::new();
    loop {
        match *bytes.get(at)? {
            0x21 => {
                let label = *bytes.get(at + 1)?;
                at += 2;
                let mut data = Vec::new();
                loop {
                    let len = *bytes.get(at)? as usize;
                    at += 1;
                    if len == 0 {
                        break;
                    }
                    data.extend_from_slice(bytes.get(at..at + len)?);
                    at += len;
                }
                if label == GIF_COMMENT {
                    comments.push(data);
                }
            }
            // An image or the trailer: the header's extensions are over.
            0x2C | 0x3B => return Some(comments),
            _ => return None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension() {
        assert_eq!(
            AnimatedFormat::from_path(Path::new("a/b.GIF")),
            Some(AnimatedFormat::Gif)
        );
        assert_eq!(
            AnimatedFormat::from_path(Path::new("b.apng")),
            Some(AnimatedFormat::Apng)
        );
        assert_eq!(AnimatedFormat::from_path(Path::new("b.png")), None);
    }

    #[test]
    fn delays() {
        assert_eq!(apng_delay(24.0), (1, 24));
        assert_eq!(apng_delay(12.5), (80, 1000));
    }

    #[test]
    fn apng_has_every_frame() {
        let mut bytes = Vec::new();
        let mut enc =
            AnimatedEncoder::new(AnimatedFormat::Apng, &mut bytes, 4, 3, 2, 10.0, false, "k")
                .unwrap();
        enc.add_frame(&Image::new(4, 3)).unwrap();
        assert!(enc.add_frame(&Image::new(3, 3)).is_err());
        enc.add_frame(&Image::new(4, 3)).unwrap();
        enc.finish().unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().unwrap();
        let control = reader.info().animation_control.unwrap();
        assert_eq!((control.num_frames, control.num_plays), (2, 0));
    }

    #[test]
    fn apng_frames_keep_alpha_and_gif_refuses_it() {
        let mut bytes = Vec::new();
        let mut enc =
            AnimatedEncoder::new(AnimatedFormat::Apng, &mut bytes, 2, 1, 1, 10.0, true, "k")
                .unwrap();
        let mut frame = Image::transparent(2, 1);
        frame.set_alpha(1, 0, 1.0);
        enc.add_frame(&frame).unwrap();
        enc.finish().unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        assert_eq!(reader.info().color_type, png::ColorType::Rgba);
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(&buf[..8], &[0, 0, 0, 0, 0, 0, 0, 255]);
        let gif = AnimatedEncoder::new(AnimatedFormat::Gif, Vec::new(), 2, 1, 1, 10.0, true, "k");
        assert!(gif.is_err());
    }

    #[test]
    fn both_formats_carry_their_key_and_decode() {
        let dir = tempfile::tempdir().unwrap();
        for (format, name) in [
            (AnimatedFormat::Gif, "a.gif"),
            (AnimatedFormat::Apng, "a.apng"),
        ] {
            let path = dir.path().join(name);
            let mut file = std::fs::File::create(&path).unwrap();
            let mut enc =
                AnimatedEncoder::new(format, &mut file, 5, 4, 2, 24.0, false, "0123abcd").unwrap();
            enc.add_frame(&Image::new(5, 4)).unwrap();
            enc.add_frame(&Image::new(5, 4)).unwrap();
            enc.finish().unwrap();
            drop(file);
            assert_eq!(read_key(&path).as_deref(), Some("0123abcd"), "{name}");
            assert!(crate::animation::is_complete_animation(&path), "{name}");
            // Cut short, the key is still there but the file is not complete.
            let bytes = std::fs::read(&path).unwrap();
            std::fs::write(&path, &bytes[..bytes.len() - 6]).unwrap();
            assert!(!crate::animation::is_complete_animation(&path), "{name}");
        }
        // A GIF with no comment, and bytes that are not a GIF.
        let plain = dir.path().join("p.gif");
        let mut bytes = Vec::new();
        {
            let mut e = gif::Encoder::new(&mut bytes, 1, 1, &[]).unwrap();
            let mut px = [0u8, 0, 0, 255];
            e.write_frame(&gif::Frame::from_rgba_speed(1, 1, &mut px, 10))
                .unwrap();
        }
        std::fs::write(&plain, &bytes).unwrap();
        assert_eq!(read_key(&plain), None);
        std::fs::write(&plain, b"GIF89a").unwrap();
        assert_eq!(read_key(&plain), None);
    }

    #[test]
    fn gif_delays_are_whole_hundredths() {
        assert_eq!(gif_delay(24.0), 4);
        assert_eq!(gif_delay(10.0), 10);
        assert_eq!(gif_delay(0.2), 100);
    }
}
