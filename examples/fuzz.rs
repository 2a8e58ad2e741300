//! The long scene-fuzzing campaign (docs/reliability.md): `cargo run --example fuzz --
//! CASES SEED [THREADS]` runs cases 0..CASES of the run SEED in the dev profile (debug
//! assertions and overflow checks on) and prints the counts: cases, parsed, rendered,
//! panics, non-finite images, malformed errors, slow cases and the slowest case.
//! `bench/fuzz.sh` drives it. Exits 1 if any case failed. `fuzz case SEED INDEX` prints one
//! case and times it; `fuzz seeds` times the unmutated base scenes.

#[path = "../tests/it/fuzz_support/mod.rs"]
mod fuzz_support;

use fuzz_support::{confirm_slow, run, Fuzzer, Tally};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A case slower than this counts as slow.
const BOUND: Duration = Duration::from_secs(2);
/// Cases per unit of parallel work.
const CHUNK: u64 = 2000;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize, default: u64| -> u64 {
        args.get(i).map_or(default, |s| {
            s.replace('_', "").parse().unwrap_or_else(|_| {
                eprintln!("usage: fuzz [CASES [SEED [THREADS]]], not `{s}`");
                std::process::exit(2)
            })
        })
    };
    if args.first().is_some_and(|a| a == "seeds") {
        time_seeds();
        return;
    }
    if args.first().is_some_and(|a| a == "case") {
        // `fuzz case SEED INDEX`: prints case INDEX of run SEED and times it.
        let (seed, index) = (number(1, 1), number(2, 0));
        let text = Fuzzer::new().case(seed, index);
        println!("{text}");
        for _ in 0..3 {
            let o = fuzz_support::run_case(&text, seed ^ index);
            println!("{:?} in {:.1} ms", o.verdict, o.elapsed.as_secs_f64() * 1e3);
        }
        return;
    }
    let (cases, seed, threads) = (number(0, 1_000_000), number(1, 1), number(2, 1));
    // Panics are expected to be rare and are counted: keep their messages off the terminal.
    std::panic::set_hook(Box::new(|_| {}));
    let fuzzer = Fuzzer::new();
    let start = Instant::now();
    // Plain threads taking chunks from a counter (not a rayon pool: a rayon worker waiting
    // for the render's own pool would run other chunks meanwhile, inside the case's time).
    let chunks = cases.div_ceil(CHUNK);
    let next = AtomicU64::new(0);
    let done = AtomicU64::new(0);
    let total = Mutex::new(Tally::default());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= chunks {
                    return;
                }
                let first = k * CHUNK;
                let t = run(&fuzzer, seed, first, CHUNK.min(cases - first), BOUND);
                let n = done.fetch_add(t.cases, Ordering::Relaxed) + t.cases;
                if n % 50_000 < CHUNK {
                    eprintln!("{n} cases, {:.0} s", start.elapsed().as_secs_f64());
                }
                total.lock().unwrap().merge(t);
            });
        }
    });
    let mut tally = total.into_inner().unwrap();
    let elapsed = start.elapsed();
    let measured_slow = tally.slow;
    let dropped = confirm_slow(&mut tally, seed, BOUND);
    println!("seed            {seed}");
    println!("cases           {}", tally.cases);
    println!("parsed          {}", tally.parsed);
    println!("rendered        {}", tally.rendered);
    println!("panics          {}", tally.panics);
    println!("non-finite      {}", tally.non_finite);
    println!("bad errors      {}", tally.bad_errors);
    println!(
        "slow (> {} s)    {} ({measured_slow} over the bound in the run, {dropped} of them \
         under it when re-timed alone)",
        BOUND.as_secs(),
        tally.slow
    );
    println!(
        "slowest case    #{} {:.1} ms",
        tally.slowest.1,
        tally.slowest.0.as_secs_f64() * 1e3
    );
    println!(
        "wall time       {:.0} s on {threads} thread(s)",
        elapsed.as_secs_f64()
    );
    for (index, verdict, text) in &tally.failures {
        println!("\n--- case #{index}: {verdict:?}\n{text}");
    }
    for (index, text) in &tally.slow_cases {
        println!("\n--- slow case #{index}\n{text}");
    }
    if !tally.clean() {
        std::process::exit(1);
    }
}

/// `fuzz seeds`: times each base scene as a case (unmutated).
fn time_seeds() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for dir in [root.clone(), root.join("implicit")] {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|e| e != "scene") {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap();
            let t = Instant::now();
            let s = kardia::scene::parse(&text, "x", &Default::default());
            let parse = t.elapsed();
            let t = Instant::now();
            let o = fuzz_support::run_case(&text, 1);
            println!(
                "{}: parse {:?} ok={} case {:?} {:?}",
                p.display(),
                parse,
                s.is_ok(),
                t.elapsed(),
                o.verdict
            );
        }
    }
    let t = Instant::now();
    let o = fuzz_support::run_case(fuzz_support::EVERY_KEYWORD, 1);
    println!("every keyword: {:?} {:?}", t.elapsed(), o.verdict);
}
