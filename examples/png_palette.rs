//! Rewrites an RGB(A) PNG as an indexed-colour PNG of at most 256 colours (NeuQuant, as the
//! GIF encoder quantises; transparency is dropped): the documentation's screenshots at a
//! fraction of their size, their text still legible.
//!
//! `cargo run --release --example png_palette -- IN.png OUT.png` prints both sizes; exits 1
//! if the image cannot be read or written or is larger than 65535 px a side.

use std::fs::File;
use std::io::BufWriter;

fn convert(input: &str, output: &str) -> Result<(u64, u64), String> {
    let rgb = image::open(input)
        .map_err(|e| format!("cannot read {input}: {e}"))?
        .to_rgb8();
    let (width, height) = rgb.dimensions();
    let side = |v: u32| u16::try_from(v).map_err(|_| format!("{input}: {v} px is too large"));
    // Speed 1: the slowest and best of NeuQuant's samplings.
    let frame = gif::Frame::from_rgb_speed(side(width)?, side(height)?, rgb.as_raw(), 1);
    let palette = frame
        .palette
        .clone()
        .ok_or_else(|| "the quantiser gave no palette".to_string())?;
    let file = File::create(output).map_err(|e| format!("cannot write {output}: {e}"))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Indexed);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_palette(palette);
    encoder.set_compression(png::Compression::High);
    let mut writer = encoder
        .write_header()
        .map_err(|e| format!("{output}: {e}"))?;
    writer
        .write_image_data(&frame.buffer)
        .map_err(|e| format!("{output}: {e}"))?;
    writer.finish().map_err(|e| format!("{output}: {e}"))?;
    let size = |path: &str| std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    Ok((size(input), size(output)))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 2 {
        eprintln!("usage: png_palette IN.png OUT.png");
        std::process::exit(2);
    }
    match convert(&args[0], &args[1]) {
        Ok((before, after)) => {
            println!("{}: {before} bytes -> {}: {after} bytes", args[0], args[1])
        }
        Err(e) => {
            eprintln!("png_palette: {e}");
            std::process::exit(1);
        }
    }
}
