//! All integration tests, one module per area, linked into one test binary.

mod heart_support;
mod render_support;

mod cli_render;
mod explore;
mod explore_browser;
mod heart_geometry;
mod heart_hard_cases;
mod heart_solvers;
mod implicit_algebra;
mod implicit_measure;
mod implicit_render;
mod implicit_scene;
mod implicit_specks;
mod probe_cli;
mod render_golden;
mod render_shading;
mod roots_cli;
mod roots_heart;
mod roots_sturm;
mod scene_errors;
mod scene_files;
mod scene_fuzz;
mod shapes_props;
mod specks;
