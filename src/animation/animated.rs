//! Animated outputs: every frame of a sequence in one file, GIF or APNG, looping forever.
//! Frames are encoded as they are handed over (8-bit sRGB, as a PNG still would store them).

use std::io::Write;
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
    Gif(Box<image::codecs::gif::GifEncoder<W>>, image::Delay),
    Apng(png::Writer<W>),
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
    /// per second into `out`; with `alpha`, an APNG of RGBA frames with straight alpha (a GIF
    /// refuses it: its transparency is only on or off).
    pub fn new(
        format: AnimatedFormat,
        out: W,
        width: u32,
        height: u32,
        frames: u32,
        fps: f64,
        alpha: bool,
    ) -> Result<Self, OutputError> {
        if alpha && format == AnimatedFormat::Gif {
            return Err(OutputError::Encode(
                "a GIF cannot hold partial transparency: use an APNG for alpha".into(),
            ));
        }
        let inner = match format {
            AnimatedFormat::Gif => {
                let mut encoder = image::codecs::gif::GifEncoder::new_with_speed(out, 10);
                encoder
                    .set_repeat(image::codecs::gif::Repeat::Infinite)
                    .map_err(encode_error)?;
                let delay = image::Delay::from_numer_denom_ms(1000, fps.round().max(1.0) as u32);
                Inner::Gif(Box::new(encoder), delay)
            }
            AnimatedFormat::Apng => {
                let mut encoder = png::Encoder::new(out, width, height);
                encoder.set_color(if alpha {
                    png::ColorType::Rgba
                } else {
                    png::ColorType::Rgb
                });
                encoder.set_depth(png::BitDepth::Eight);
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
                let rgba: Vec<u8> = rgb
                    .chunks_exact(3)
                    .flat_map(|p| [p[0], p[1], p[2], 255])
                    .collect();
                let buffer = image::RgbaImage::from_raw(self.width, self.height, rgba)
                    .ok_or_else(|| encode_error("frame buffer of the wrong size"))?;
                encoder
                    .encode_frame(image::Frame::from_parts(buffer, 0, 0, *delay))
                    .map_err(encode_error)
            }
            Inner::Apng(writer) => writer.write_image_data(&rgb).map_err(encode_error),
        }
    }

    /// Ends the file (every frame must have been added).
    pub fn finish(self) -> Result<(), OutputError> {
        match self.inner {
            Inner::Gif(encoder, _) => {
                drop(encoder); // the GIF trailer is written on drop
                Ok(())
            }
            Inner::Apng(writer) => writer.finish().map_err(encode_error),
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
            AnimatedEncoder::new(AnimatedFormat::Apng, &mut bytes, 4, 3, 2, 10.0, false).unwrap();
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
            AnimatedEncoder::new(AnimatedFormat::Apng, &mut bytes, 2, 1, 1, 10.0, true).unwrap();
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
        let gif = AnimatedEncoder::new(AnimatedFormat::Gif, Vec::new(), 2, 1, 1, 10.0, true);
        assert!(gif.is_err());
    }
}
