//! The film (a linear-RGB pixel buffer), its 8-bit sRGB conversion, and writing it out.
//!
//! The film stores each channel as an `f32` (12 bytes a pixel): shading is done in `f64`, and
//! each pixel's final value is rounded to the nearest `f32` once, when it is stored (by
//! [`to_stored`]). (That can move a value across an 8-bit sRGB code boundary: measured, 1 pixel
//! in 2.56 million of the benchmark heart and 2 in 640,000 of the default scene change by one
//! 8-bit step.) EXR output is `f32` or `f16` anyway.
//!
//! The film never stores NaN or infinity, whatever the scene: at store time a NaN channel
//! becomes 0 and a channel beyond the `f32` range becomes `±f32::MAX` ([`to_stored`]).
//!
//! An image may carry coverage ([`Image::alpha`], a transparent background): then its colours
//! are premultiplied (the background's samples contribute nothing) and each pixel has the
//! fraction of its samples whose camera ray hit an object. PNG stores that as straight
//! (unassociated) 8-bit alpha, as the PNG specification says ([`Image::to_srgba8`]); EXR
//! stores the premultiplied colours and the A channel, as OpenEXR's convention says.
//!
//! Output: [`encode_png`] and [`encode_exr`] write an image to any writer,
//! [`encode_png_streaming`] compresses a PNG's rows while they are still being rendered, and
//! [`AtomicFile`] makes a file appear complete or not at all.

mod atomic;
mod encode;
mod png_filter;
mod srgb;

pub use atomic::{check_output_path, remove_stale_temporaries, AtomicFile};
pub(crate) use encode::read_png_tag;
pub use encode::{
    encode, encode_exr, encode_exr_tagged, encode_png, encode_png_srgb8, encode_png_streaming,
    encode_png_streaming_tagged, encode_tagged, read_tag, write_image, write_image_as, FileTag,
    ImageFormat, OutputError, RowSink,
};
pub use srgb::{linear_to_srgb8, srgb8_to_linear};
pub(crate) use srgb::{srgb8_into, srgba8_into};

use crate::geometry::DVec3;
/// The film's pixel type: linear RGB, one `f32` a channel.
pub use glam::Vec3;

/// A rendered image: `width × height` linear-RGB pixels, row-major, top row first, each
/// channel stored as an `f32` (the nearest to the `f64` value rendered), and optionally the
/// coverage of each pixel (`alpha`).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, `width·height` of them, row-major from the top-left; linear RGB in `f32`,
    /// unclamped (values above 1 and negative values are kept as rendered). Everything the
    /// renderer and [`Image::set`] store is finite (see [`to_stored`]). With `alpha`, these
    /// are premultiplied: a pixel's colour already weighted by its coverage.
    pub pixels: Vec<Vec3>,
    /// `None`: an opaque image (the scene's background fills the misses). `Some`: one value
    /// a pixel, in the order of `pixels`, each in `[0, 1]` (never NaN): the fraction of the
    /// pixel's samples whose camera ray hit an object, 0 where only background was seen.
    pub alpha: Option<Vec<f32>>,
}

/// `count` black pixels, in memory the allocator hands out already zeroed: no page of it is
/// written here, so the render's threads fault their own rows in, in parallel (`vec!` of a
/// `Vec3` writes every pixel first, on one thread: 14 ms at the start of a 1600×1600 render).
fn zeroed_pixels(count: usize) -> Vec<Vec3> {
    let layout = std::alloc::Layout::array::<Vec3>(count).expect("image too large");
    if layout.size() == 0 {
        return Vec::new();
    }
    // SAFETY: the layout is non-empty and is the one `Vec<Vec3>` uses for `count` elements;
    // all-zero bytes are a valid `Vec3` (three `f32` zeros), so the `count` elements are
    // initialised; a null pointer (allocation failure) is handled before use.
    unsafe {
        let ptr = std::alloc::alloc_zeroed(layout).cast::<Vec3>();
        if ptr.is_null() {
            std::alloc::handle_alloc_error(layout);
        }
        Vec::from_raw_parts(ptr, count, count)
    }
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: zeroed_pixels(width as usize * height as usize),
            alpha: None,
        }
    }

    /// A fully transparent image of the given size (colour 0 and alpha 0 everywhere).
    pub fn transparent(width: u32, height: u32) -> Self {
        let count = width as usize * height as usize;
        Self {
            width,
            height,
            pixels: zeroed_pixels(count),
            alpha: Some(vec![0.0; count]),
        }
    }

    /// The coverage of the pixel at column `x`, row `y`: its alpha, or 1 in an opaque image.
    /// Panics outside the image.
    pub fn alpha_at(&self, x: u32, y: u32) -> f64 {
        assert!(x < self.width && y < self.height, "pixel out of range");
        let index = y as usize * self.width as usize + x as usize;
        self.alpha.as_ref().map_or(1.0, |a| a[index] as f64)
    }

    /// Stores the coverage `alpha` of the pixel at column `x`, row `y`, clamped to `[0, 1]`
    /// (NaN stored as 0), making the image one with alpha (every other pixel opaque) if it
    /// was not. Panics outside the image.
    pub fn set_alpha(&mut self, x: u32, y: u32, alpha: f64) {
        assert!(x < self.width && y < self.height, "pixel out of range");
        let index = y as usize * self.width as usize + x as usize;
        let count = self.pixels.len();
        self.alpha.get_or_insert_with(|| vec![1.0; count])[index] = to_stored_alpha(alpha);
    }

    /// The pixel at column `x`, row `y` (row 0 at the top), widened exactly from the stored
    /// `f32`s. Panics outside the image.
    pub fn get(&self, x: u32, y: u32) -> DVec3 {
        assert!(x < self.width && y < self.height, "pixel out of range");
        self.pixels[y as usize * self.width as usize + x as usize].as_dvec3()
    }

    /// Stores `value` (linear RGB) at column `x`, row `y`, each channel rounded to the nearest
    /// `f32` and made finite as [`to_stored`] says. Panics outside the image.
    pub fn set(&mut self, x: u32, y: u32, value: DVec3) {
        assert!(x < self.width && y < self.height, "pixel out of range");
        self.pixels[y as usize * self.width as usize + x as usize] = to_stored(value);
    }

    /// The pixels of `region` as an image of its own. Panics unless the region lies inside.
    pub fn crop(&self, region: Region) -> Image {
        assert!(region.fits(self.width, self.height), "region out of range");
        let (w, rw) = (self.width as usize, region.width as usize);
        let rows = |row: usize| {
            let start = (region.y as usize + row) * w + region.x as usize;
            start..start + rw
        };
        let height = region.height as usize;
        Image {
            width: region.width,
            height: region.height,
            pixels: (0..height)
                .flat_map(|row| self.pixels[rows(row)].iter().copied())
                .collect(),
            alpha: self.alpha.as_ref().map(|alpha| {
                (0..height)
                    .flat_map(|row| alpha[rows(row)].iter().copied())
                    .collect()
            }),
        }
    }

    /// Copies `tile` into this image with its top-left corner at column `x`, row `y` (e.g. a
    /// rendered region back into the full image at the region's corner), alpha included.
    /// Panics unless the tile lies inside and both images have alpha or neither has.
    pub fn paste(&mut self, x: u32, y: u32, tile: &Image) {
        let at = Region {
            x,
            y,
            width: tile.width,
            height: tile.height,
        };
        assert!(at.fits(self.width, self.height), "tile out of range");
        assert_eq!(
            self.alpha.is_some(),
            tile.alpha.is_some(),
            "a tile with alpha pasted into an image without, or the other way round"
        );
        let (w, tw) = (self.width as usize, tile.width as usize);
        for (row, src) in tile.pixels.chunks_exact(tw.max(1)).enumerate() {
            let start = (y as usize + row) * w + x as usize;
            self.pixels[start..start + tw].copy_from_slice(src);
        }
        if let (Some(dst), Some(src)) = (self.alpha.as_mut(), tile.alpha.as_ref()) {
            for (row, src) in src.chunks_exact(tw.max(1)).enumerate() {
                let start = (y as usize + row) * w + x as usize;
                dst[start..start + tw].copy_from_slice(src);
            }
        }
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

    /// The image as 8-bit sRGB bytes with straight (unassociated) alpha, `R, G, B, A` per
    /// pixel, row-major: the colour of the covered part of each pixel (its premultiplied
    /// colour divided by its coverage, then as [`Image::to_srgb8`]) and the coverage rounded to
    /// the nearest of 0 ..= 255. A pixel whose alpha rounds to 0 is `0, 0, 0, 0`; an opaque
    /// image gives alpha 255 everywhere and the colours of [`Image::to_srgb8`].
    pub fn to_srgba8(&self) -> Vec<u8> {
        use rayon::prelude::*;
        let mut bytes = vec![0u8; self.pixels.len() * 4];
        let chunk = 4096;
        bytes
            .par_chunks_mut(4 * chunk)
            .zip(self.pixels.par_chunks(chunk))
            .enumerate()
            .for_each(|(i, (out, px))| {
                let alpha = self
                    .alpha
                    .as_ref()
                    .map(|a| &a[i * chunk..i * chunk + px.len()]);
                srgba8_into(px, alpha, out);
            });
        bytes
    }
}

/// A rectangle of pixels of an image: columns `x .. x + width`, rows `y .. y + height` (row 0
/// at the top).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Region {
    /// First column.
    pub x: u32,
    /// First row (0 = top).
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl Region {
    /// The whole of a `width × height` image.
    pub fn full(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// Whether the region is non-empty and lies inside a `width × height` image.
    pub fn fits(&self, width: u32, height: u32) -> bool {
        self.width > 0
            && self.height > 0
            && self.x as u64 + self.width as u64 <= width as u64
            && self.y as u64 + self.height as u64 <= height as u64
    }

    /// Pixels in the region.
    pub fn pixel_count(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
}

/// The value the film stores for a rendered linear-RGB `value`: each channel rounded to the
/// nearest `f32`, a NaN channel stored as 0 and a channel beyond the `f32` range (including
/// ±infinity) as `±f32::MAX`. Finite values within range are only rounded, so every stored
/// pixel is finite.
#[inline]
pub fn to_stored(value: DVec3) -> Vec3 {
    let rounded = value.as_vec3();
    if rounded.is_finite() {
        return rounded;
    }
    let channel = |v: f64| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-f32::MAX as f64, f32::MAX as f64) as f32
        }
    };
    Vec3::new(channel(value.x), channel(value.y), channel(value.z))
}

/// The value the film stores for a coverage `alpha`: clamped to `[0, 1]`, NaN as 0.
#[inline]
pub fn to_stored_alpha(alpha: f64) -> f32 {
    if alpha.is_nan() {
        0.0
    } else {
        alpha.clamp(0.0, 1.0) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_pixels_are_finite() {
        let stored = to_stored(DVec3::new(f64::NAN, f64::INFINITY, -1e300));
        assert_eq!(stored, Vec3::new(0.0, f32::MAX, -f32::MAX));
        let exact = DVec3::new(0.25, 1e30, -3.5);
        assert_eq!(to_stored(exact), exact.as_vec3());
        let mut img = Image::new(1, 1);
        img.set(0, 0, DVec3::splat(f64::NAN));
        assert_eq!(img.pixels[0], Vec3::ZERO);
    }

    #[test]
    fn alpha_is_stored_in_range_and_follows_crop_and_paste() {
        let mut img = Image::new(4, 3);
        assert_eq!(img.alpha_at(1, 1), 1.0, "opaque without alpha");
        img.set_alpha(1, 1, 0.25);
        assert_eq!(img.alpha_at(1, 1), 0.25);
        assert_eq!(img.alpha_at(0, 0), 1.0, "the others stay opaque");
        img.set_alpha(2, 1, f64::NAN);
        img.set_alpha(3, 1, 7.0);
        img.set_alpha(0, 2, -1.0);
        assert_eq!(
            (img.alpha_at(2, 1), img.alpha_at(3, 1), img.alpha_at(0, 2)),
            (0.0, 1.0, 0.0)
        );
        let region = Region {
            x: 1,
            y: 1,
            width: 3,
            height: 2,
        };
        let tile = img.crop(region);
        assert_eq!(tile.alpha_at(0, 0), 0.25);
        let mut back = Image::transparent(4, 3);
        back.paste(1, 1, &tile);
        assert_eq!(back.crop(region), tile);
        assert_eq!(back.alpha_at(0, 0), 0.0);
        let rgba = img.to_srgba8();
        assert_eq!(&rgba[..4], &[0, 0, 0, 255]);
        assert_eq!(&rgba[4 * 5..4 * 5 + 4], &[0, 0, 0, 64]);
        assert_eq!(&rgba[4 * 6..4 * 6 + 4], &[0, 0, 0, 0]);
        assert_eq!(
            Image::new(2, 1).to_srgba8(),
            vec![0, 0, 0, 255, 0, 0, 0, 255]
        );
    }

    #[test]
    fn crop_and_paste_are_inverse() {
        let mut img = Image::new(5, 4);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = Vec3::splat(i as f32);
        }
        let region = Region {
            x: 1,
            y: 2,
            width: 3,
            height: 2,
        };
        let tile = img.crop(region);
        assert_eq!((tile.width, tile.height), (3, 2));
        assert_eq!(tile.pixels[0], Vec3::splat(11.0));
        assert_eq!(tile.pixels[5], Vec3::splat(18.0));
        let mut back = Image::new(5, 4);
        back.paste(1, 2, &tile);
        assert_eq!(back.crop(region), tile);
        assert!(!region.fits(3, 4) && region.fits(4, 4));
        assert!(!Region::full(0, 3).fits(0, 3));
    }
}
