//! kardia's PNG files are byte for byte what the png crate's own stream writer makes of the
//! same pixels with kardia's settings (8-bit RGB or RGBA, `Compression::Fast`: the adaptive
//! filter and fdeflate, the render key in a `tEXt` chunk): kardia filters the rows itself
//! (`film::png_filter`) and must not change a file. Every shipped scene, opaque and with
//! alpha, at an odd size, on the processor's fastest path and on `KARDIA_CPU=baseline`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The `.scene` files of `scenes/` and `scenes/implicit/`.
fn shipped_scenes() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes = Vec::new();
    for dir in [root.clone(), root.join("implicit")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "scene") {
                scenes.push(path);
            }
        }
    }
    scenes.sort();
    scenes
}

/// The PNG the png crate writes itself for the pixels and text chunks of `file`, with the
/// settings kardia writes with.
fn png_crates_own(file: &[u8]) -> Vec<u8> {
    let mut reader = png::Decoder::new(std::io::Cursor::new(file))
        .read_info()
        .unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut pixels).unwrap();
    pixels.truncate(frame.buffer_size());
    let info = reader.info();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, info.width, info.height);
    for text in &info.uncompressed_latin1_text {
        encoder
            .add_text_chunk(text.keyword.clone(), text.text.clone())
            .unwrap();
    }
    encoder.set_color(info.color_type);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    stream.write_all(&pixels).unwrap();
    stream.finish().unwrap();
    writer.finish().unwrap();
    out
}

#[test]
fn every_shipped_scene_renders_to_the_png_crates_own_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 15, "only {} scenes found", scenes.len());
    let mut checked = 0;
    for scene in &scenes {
        let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
        for alpha in [false, true] {
            for baseline in [false, true] {
                let out = dir.path().join(format!("{name}-{alpha}-{baseline}.png"));
                let mut command = Command::new(env!("CARGO_BIN_EXE_kardia"));
                command.args(["render", "--width", "67", "--height", "45", "--spp", "1"]);
                command
                    .args(["--quiet", "--frame", "0", "-o"])
                    .arg(&out)
                    .arg(scene);
                if alpha {
                    command.arg("--alpha");
                }
                if baseline {
                    command.env("KARDIA_CPU", "baseline");
                } else {
                    command.env_remove("KARDIA_CPU");
                }
                let run = command.output().unwrap();
                assert!(
                    run.status.success(),
                    "{name}: {}",
                    String::from_utf8_lossy(&run.stderr)
                );
                let ours = std::fs::read(&out).unwrap();
                let theirs = png_crates_own(&ours);
                assert!(
                    ours == theirs,
                    "{name} (alpha {alpha}, baseline {baseline}): {} bytes, the png crate's {}",
                    ours.len(),
                    theirs.len()
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4 * scenes.len());
}
