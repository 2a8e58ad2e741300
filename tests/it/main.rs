//! All integration tests, one module per area, linked into one test binary.

mod fuzz_support;
mod heart_support;
mod render_support;

mod anim_cli;
mod anim_scene;
mod cli_render;
mod explore;
mod explore_browser;
mod farm;
mod fuzz_scenes;
mod heart_geometry;
mod heart_hard_cases;
mod heart_solvers;
mod implicit_algebra;
mod implicit_measure;
mod implicit_render;
mod implicit_scene;
mod implicit_specks;
mod pipeline;
mod probe_cli;
mod render_golden;
mod render_shading;
mod roots_cli;
mod roots_heart;
mod roots_reference;
mod roots_sturm;
mod roots_trace;
mod scene_errors;
mod scene_files;
mod scene_fuzz;
mod scene_lanes;
mod scene_ranges;
mod shapes_props;
mod specks;
mod study_views;
