//! Compares two renders of the same framing: how many pixels the silhouettes disagree on, and
//! how many numerical specks each image has (see `kardia::analysis`).
//!
//! `cargo run --release --example imgcompare -- A.png B.png` prints one line per image and one
//! for the silhouette difference; exits 1 if an image cannot be read or the sizes differ.

use kardia::analysis::Rgb8;

fn load(path: &str) -> Result<(usize, usize, Vec<[u8; 3]>), String> {
    let img = image::open(path)
        .map_err(|e| format!("cannot read {path}: {e}"))?
        .to_rgb8();
    let (w, h) = img.dimensions();
    Ok((w as usize, h as usize, img.pixels().map(|p| p.0).collect()))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 2 {
        eprintln!("usage: imgcompare A.png B.png");
        std::process::exit(2);
    }
    let run = || -> Result<(), String> {
        let a = load(&args[0])?;
        let b = load(&args[1])?;
        if (a.0, a.1) != (b.0, b.1) {
            return Err(format!("sizes differ: {}x{} and {}x{}", a.0, a.1, b.0, b.1));
        }
        let mut masks = Vec::new();
        for (path, (w, h, px)) in [(&args[0], &a), (&args[1], &b)] {
            let img = Rgb8 {
                width: *w,
                height: *h,
                pixels: px,
            };
            let mask = img.silhouette([0, 0, 0], 8);
            let area = mask.iter().filter(|&&m| m).count();
            println!(
                "{path}: {area} object pixels, {} specks",
                img.specks(&mask).len()
            );
            masks.push(mask);
        }
        let differ = masks[0]
            .iter()
            .zip(&masks[1])
            .filter(|(x, y)| x != y)
            .count();
        let area = masks[0].iter().filter(|&&m| m).count().max(1);
        println!(
            "silhouettes differ on {differ} pixels ({:.3}% of the first object's area)",
            100.0 * differ as f64 / area as f64
        );
        Ok(())
    };
    if let Err(e) = run() {
        eprintln!("imgcompare: {e}");
        std::process::exit(1);
    }
}
