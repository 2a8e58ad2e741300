//! kardia: a ray tracer for the paper "Tracing an Implicit Heart" and, beyond it, for implicit
//! polynomial surfaces. See ARCHITECTURE.md for how a ray flows through the modules.

#![warn(missing_docs)]

pub mod analysis;
pub mod animation;
pub mod camera;
pub mod cli;
pub mod explore;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod lights;
pub mod materials;
pub mod pipeline;
pub mod roots;
pub mod scene;
pub mod shapes;
pub mod tiles;
