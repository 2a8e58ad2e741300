//! kardia: a ray tracer for the paper "Tracing an Implicit Heart" and, beyond it, for implicit
//! polynomial surfaces. See ARCHITECTURE.md for how a ray flows through the modules.

#![warn(missing_docs)]

pub mod analysis;
pub mod animation;
pub mod bvh;
pub mod camera;
pub mod cli;
pub mod explore;
pub mod film;
pub mod formats;
pub mod geometry;
pub mod integrator;
pub mod lights;
pub mod materials;
pub mod mesh;
pub mod pipeline;
pub mod roots;
pub mod scene;
pub mod shapes;
pub mod tiles;

/// Helpers shared by the unit tests.
#[cfg(test)]
pub(crate) mod testing {
    /// A deterministic xorshift64 stream of numbers uniform in `[0, 1)` from `seed` (not
    /// zero).
    pub(crate) fn uniform_stream(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }
}
