//! Times kardia's PNG encoder (`film::encode_png_srgb8`: its own row filter, then fdeflate)
//! against the png crate's `StreamWriter` with the same settings, on the pixels of the given
//! 8-bit RGB(A) PNGs, and checks that both write the same bytes.
//!
//! `cargo run --release --example png_encode -- IMAGE.png…` prints, for each image, the
//! medians of 31 interleaved encodings of each (this thread's CPU time on Linux, which other
//! processes disturb less than the wall time it gives elsewhere; `KARDIA_CPU=baseline` times
//! kardia's baseline copy); exits 1 if an image cannot be read or the bytes differ.

use std::io::Write;

/// Seconds of CPU time of the calling thread (Linux: `CLOCK_THREAD_CPUTIME_ID`), or of wall
/// time since the first call elsewhere.
fn clock() -> f64 {
    #[cfg(target_os = "linux")]
    {
        #[repr(C)]
        struct Timespec {
            seconds: i64,
            nanoseconds: i64,
        }
        extern "C" {
            fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
        }
        const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
        let mut time = Timespec {
            seconds: 0,
            nanoseconds: 0,
        };
        // SAFETY: clock_gettime writes one timespec (two 64-bit fields on 64-bit Linux).
        if unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut time) } == 0 {
            return time.seconds as f64 + time.nanoseconds as f64 * 1e-9;
        }
    }
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs_f64()
}

/// The pixels, size, colour type and text chunks of a PNG file.
struct Decoded {
    pixels: Vec<u8>,
    width: u32,
    height: u32,
    alpha: bool,
    text: Vec<(String, String)>,
}

fn decode(path: &str) -> Result<Decoded, String> {
    let file = std::fs::read(path).map_err(|e| format!("cannot read {path}: {e}"))?;
    let mut reader = png::Decoder::new(std::io::Cursor::new(file))
        .read_info()
        .map_err(|e| format!("{path}: {e}"))?;
    let mut pixels = vec![0; reader.output_buffer_size().ok_or("too large")?];
    let frame = reader
        .next_frame(&mut pixels)
        .map_err(|e| format!("{path}: {e}"))?;
    pixels.truncate(frame.buffer_size());
    let info = reader.info();
    let alpha = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => false,
        (png::ColorType::Rgba, png::BitDepth::Eight) => true,
        other => return Err(format!("{path}: {other:?} is not 8-bit RGB(A)")),
    };
    let text = info
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    Ok(Decoded {
        pixels,
        width: info.width,
        height: info.height,
        alpha,
        text,
    })
}

/// The png crate's own stream writer with kardia's settings, fed 16 rows at a time.
fn png_crates_own(image: &Decoded, tag: Option<kardia::film::FileTag>) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, image.width, image.height);
    if let Some(tag) = tag {
        encoder
            .add_text_chunk(tag.name.into(), tag.text.into())
            .unwrap();
    }
    encoder.set_color(if image.alpha {
        png::ColorType::Rgba
    } else {
        png::ColorType::Rgb
    });
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let row = image.pixels.len() / image.height as usize;
    for rows in image.pixels.chunks(16 * row) {
        stream.write_all(rows).unwrap();
    }
    stream.finish().unwrap();
    writer.finish().unwrap();
    out
}

fn median_ms(times: &mut [f64]) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2] * 1e3
}

fn run(path: &str) -> Result<(), String> {
    let image = decode(path)?;
    let tag = image
        .text
        .first()
        .map(|(name, text)| kardia::film::FileTag {
            name: name.as_str(),
            text: text.as_str(),
        });
    let (mut theirs, mut ours) = (Vec::new(), Vec::new());
    for _ in 0..31 {
        let start = clock();
        let reference = png_crates_own(&image, tag);
        theirs.push(clock() - start);
        let start = clock();
        let mut out = Vec::with_capacity(reference.len());
        kardia::film::encode_png_srgb8(
            &image.pixels,
            image.width,
            image.height,
            image.alpha,
            tag,
            &mut out,
        )
        .map_err(|e| e.to_string())?;
        ours.push(clock() - start);
        if out != reference {
            return Err(format!(
                "{path}: kardia's bytes differ from the png crate's"
            ));
        }
    }
    println!(
        "{path}: {}×{}, the png crate {:.2} ms, kardia ({}) {:.2} ms",
        image.width,
        image.height,
        median_ms(&mut theirs),
        kardia::cpu::path_name(),
        median_ms(&mut ours)
    );
    Ok(())
}

fn main() {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.is_empty() {
        eprintln!("usage: png_encode IMAGE.png…");
        std::process::exit(2);
    }
    for path in &paths {
        if let Err(e) = run(path) {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
