//! `kardia mesh`: a scene's HEART and IMPLICIT objects (or one equation or preset) as a
//! closed, manifold triangle mesh in STL, 3MF, OBJ or PLY. Parses, calls [`crate::mesh`],
//! prints a summary.

use crate::geometry::Frame;
use crate::mesh::write::{write_file, MeshFormat, MeshMetadata};
use crate::mesh::{mesh_solids, MeshRequest, NamedSolid, SolidKind};
use crate::scene::{self, LoadOptions};
use crate::shapes::{Implicit, Shape};
use clap::Args;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `kardia mesh`.
#[derive(Debug, Args)]
pub struct MeshArgs {
    /// Scene file whose HEART and IMPLICIT objects are meshed (or use --equation / --preset).
    pub scene: Option<PathBuf>,
    /// Output file: .stl (binary), .3mf, .obj or .ply (binary).
    #[arg(short, long, value_name = "FILE", required_unless_present = "measure")]
    pub output: Option<PathBuf>,
    /// An equation in x, y, z to mesh instead of a scene, e.g. "x^4 + y^4 + z^4 = 1".
    #[arg(long, conflicts_with_all = ["scene", "preset"])]
    pub equation: Option<String>,
    /// A preset and its parameters instead of a scene, e.g. --preset kummer 1.3.
    #[arg(long, num_args = 1.., value_name = "NAME PARAMS",
          conflicts_with = "scene")]
    pub preset: Option<Vec<String>>,
    /// Clip radius for --equation or --preset (object units; default: the preset's, or one
    /// derived for a bounded surface).
    #[arg(long, value_name = "R")]
    pub bound: Option<f64>,
    /// Grid accuracy in scene units (default: 1% of each object's clip radius).
    #[arg(long, value_name = "T")]
    pub tolerance: Option<f64>,
    /// Scale so the largest extent is MM millimetres (placed at the origin).
    #[arg(long, value_name = "MM")]
    pub size: Option<f64>,
    /// The solid inside the surface (f ≤ 0) and the clip ball: the default.
    #[arg(long, conflicts_with_all = ["outside", "shell"])]
    pub solid: bool,
    /// The solid outside the surface (f ≥ 0) within the clip ball.
    #[arg(long, conflicts_with = "shell")]
    pub outside: bool,
    /// A wall of thickness T (scene units) about the surface instead of a solid.
    #[arg(long, value_name = "T")]
    pub shell: Option<f64>,
    /// The most grid cells along a side.
    #[arg(long, value_name = "N", default_value_t = 512)]
    pub max_cells: usize,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Instead of meshing, measure the mesh in FILE (STL, OBJ or PLY, scene units) against the
    /// exact surface of --equation or --preset as kardia measures its own meshes (the
    /// Hausdorff estimate at the grid step of --tolerance); -o is then not written.
    #[arg(long, value_name = "FILE", conflicts_with = "scene")]
    pub measure: Option<PathBuf>,
}

/// The default colour of an equation or preset (a warm orange), as sRGB bytes.
const DEFAULT_COLOUR: [u8; 3] = [230, 150, 60];

fn solids(args: &MeshArgs) -> Result<Vec<NamedSolid>, String> {
    let single = |name: String, shape: Implicit| -> Result<Vec<NamedSolid>, String> {
        let solid = shape
            .polynomial_solid()
            .ok_or("an implicit surface has a polynomial")?;
        Ok(vec![NamedSolid {
            name,
            solid,
            colour: DEFAULT_COLOUR,
        }])
    };
    if let Some(eq) = &args.equation {
        let shape = Implicit::new(eq, Frame::identity(), args.bound)
            .map_err(|e| format!("--equation: {}", e.message))?;
        return single(format!("\"{eq}\""), shape);
    }
    if let Some(p) = &args.preset {
        let params = p[1..]
            .iter()
            .map(|s| {
                s.parse::<f64>()
                    .map_err(|_| format!("--preset: {s:?} is not a number"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let shape = Implicit::from_preset(&p[0], &params, Frame::identity(), args.bound)
            .map_err(|e| format!("--preset: {e}"))?;
        return single(p.join(" "), shape);
    }
    let Some(path) = &args.scene else {
        return Err("give a SCENE file, --equation \"…\" or --preset NAME PARAMS".into());
    };
    let scene = scene::parse_file(path, &LoadOptions::default())
        .map_err(|e| format!("{:?}", miette::Report::new(e)))?;
    Ok(crate::mesh::scene_solids(&scene))
}

/// Runs `kardia mesh`; returns the exit code (0 written, 1 bad arguments, scene or a mesh that
/// could not be made; nothing is written then).
pub fn run(args: MeshArgs) -> i32 {
    match mesh(&args) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("kardia mesh: {e}");
            1
        }
    }
}

fn mesh(args: &MeshArgs) -> Result<(), String> {
    let started = Instant::now();
    let kind = match (args.outside, args.shell) {
        (_, Some(thickness)) => SolidKind::Shell { thickness },
        (true, None) => SolidKind::Outside,
        (false, None) => SolidKind::Inside,
    };
    if let Some(file) = &args.measure {
        return measure(args, file, kind, started);
    }
    let output = args.output.as_ref().ok_or("give the output file with -o")?;
    let format = MeshFormat::from_path(output)?;
    let solids = solids(args)?;
    let request = MeshRequest {
        kind,
        tolerance: args.tolerance,
        max_cells: args.max_cells,
    };
    let bar = if args.quiet || !std::io::stderr().is_terminal() {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::with_draw_target(Some(1), indicatif::ProgressDrawTarget::stderr())
    };
    let count = solids.len();
    let printable = mesh_solids(&solids, &request, args.size, &|i, done, total| {
        bar.set_length((total * count) as u64);
        bar.set_position((i * total + done) as u64);
    })
    .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let meta = MeshMetadata::of_solids(&solids, args.size.is_some());
    let writing = Instant::now();
    write_file(&printable.mesh, &meta, format, output).map_err(|e| e.to_string())?;
    let write_time = writing.elapsed();
    let v = printable.verified;
    outln!(
        "kardia mesh: wrote {} ({} triangles, {} vertices, {} component{}, volume {:.6}{})",
        output.display(),
        v.triangles,
        v.vertices,
        v.components,
        if v.components == 1 { "" } else { "s" },
        v.volume,
        if args.size.is_some() { " mm³" } else { "" },
    );
    outln!(
        "  checked: closed (every edge in two triangles), one fan per vertex, outward \
         (positive volume), no zero-area triangles, no self-intersections; Euler \
         characteristic {}",
        v.euler_characteristic
    );
    for (s, part) in solids.iter().zip(&printable.parts) {
        let d = &part.deviation;
        match &part.refined {
            Some(r) => {
                outln!(
                    "  {}: tolerance {:.3e}, tetrahedra of a {}³ grid (step {:.3e} in object \
                     units) bisected where needed down to step {:.3e} (the proofs of \
                     emptiness to {:.3e}): {} leaves ({} on a uniform grid of step {:.3e}), \
                     {} of them cut by the boundary",
                    s.name,
                    part.tolerance,
                    r.coarse.cells,
                    r.coarse.step(),
                    r.cube_side(r.crossed_by_level.len() - 1),
                    r.floor_side(),
                    r.leaves(),
                    r.uniform_leaves(),
                    r.floor_side(),
                    r.crossed()
                );
                let by_side: Vec<String> = (0..r.crossed_by_level.len())
                    .step_by(3)
                    .map(|level| {
                        let n: usize = r.crossed_by_level
                            [level..(level + 3).min(r.crossed_by_level.len())]
                            .iter()
                            .sum();
                        format!("{:.3e}: {n}", r.cube_side(level))
                    })
                    .collect();
                outln!(
                    "    cut leaves by cube side: {}; bisected for a triangle's deviation {}, an \
                     edge crossed twice {}, surface not proven absent {}, a chamfered crease {} \
                     ({} rounds)",
                    by_side.join(", "),
                    r.refined_for[0],
                    r.refined_for[1],
                    r.refined_for[2],
                    r.refined_for[3],
                    r.rounds
                );
            }
            None => outln!(
                "  {}: tolerance {:.3e}, uniform grid {}³ of the floor step {:.3e} (object units)",
                s.name,
                part.tolerance,
                part.grid.cells,
                part.grid.step()
            ),
        }
        match part.coarsened {
            Some(c) => outln!(
                "    coarsened where flat: {} triangles from marching tetrahedra's {} ({} \
                 collapses and {} flips in {} passes, {} of them redone for a crossing, each new \
                 triangle within {:.3e} of the surface)",
                part.mesh.triangles.len(),
                part.extracted_triangles,
                c.done.collapses,
                c.done.flips,
                c.done.passes,
                c.done.redone,
                c.budget
            ),
            None => outln!(
                "    not coarsened: the coarsened mesh had crossing triangles at every budget \
                 tried, so marching tetrahedra's {} triangles are kept",
                part.extracted_triangles
            ),
        }
        if part.kinds.contains(&crate::mesh::VertexKind::Cap) {
            outln!(
                "    crease: {} vertices on both the surface and the clip sphere; {} triangles \
                 join a surface vertex to a cap vertex",
                part.crease_vertices(),
                part.mixed_triangles()
            );
        }
        if d.measured {
            outln!(
                "    deviation (scene units, by the root finder): surface vertices ≤ {:.2e} \
                 ({} measured, {} beyond the tolerance, {} at a node: f zero to rounding); Hausdorff estimate {:.2e} \
                 (mesh→surface {:.2e}, surface→mesh {:.2e} from {} surface samples{}{})",
                d.vertex,
                d.vertices,
                d.vertices_beyond,
                d.vertices_at_rounding,
                d.hausdorff(),
                d.mesh_to_surface,
                d.surface_to_mesh,
                d.surface_samples,
                if d.beyond_reach > 0 {
                    format!(", {} samples beyond reach", d.beyond_reach)
                } else {
                    String::new()
                },
                if d.touching_samples > 0 {
                    format!(
                        "; {} roots where f touches 0 without changing sign, on no solid's \
                         boundary, left out",
                        d.touching_samples
                    )
                } else {
                    String::new()
                }
            );
            if d.thin_samples > 0 {
                outln!(
                    "    {} sample{} beyond the tolerance lie where the solid or a gap in it is \
                     thinner than the grid step {:.3e} (beside a singular point or curve, \
                     where sheets nearly touch, or where the surface meets the clip sphere at \
                     a glancing angle), which the grid closes or opens; elsewhere the largest \
                     distance is {:.2e}",
                    d.thin_samples,
                    if d.thin_samples == 1 { "" } else { "s" },
                    d.thin_width,
                    d.away_from_thin
                );
            }
            if d.away_from_thin > part.tolerance {
                outln!(
                    "    beyond the tolerance {:.3e} away from thin parts too ({:.2e}): a \
                     smaller --tolerance refines the grid",
                    part.tolerance,
                    d.away_from_thin
                );
            }
        } else {
            outln!("    deviation not measured (the shell's polynomial is above degree 16)");
        }
    }
    outln!(
        "  singular points (nodes, pinches) are decided by the grid's labels: each is opened \
         or closed within one grid step, never left non-manifold"
    );
    if printable.scale != 1.0 {
        outln!(
            "  scaled by {:.6} to {} mm (box from the origin; deviations above are before scaling)",
            printable.scale,
            args.size.unwrap_or(0.0)
        );
    }
    let sum = |stage: fn(&crate::mesh::StageTimes) -> std::time::Duration| {
        printable
            .parts
            .iter()
            .map(|p| stage(&p.times))
            .sum::<std::time::Duration>()
            .as_secs_f64()
    };
    outln!(
        "  time {:.3} s: meshing {:.3} s (extraction {:.3} s, coarsening {:.3} s), measurement \
         {:.3} s, check {:.3} s, write {:.3} s",
        started.elapsed().as_secs_f64(),
        sum(|t| t.meshing()),
        sum(|t| t.extraction),
        sum(|t| t.coarsening),
        sum(|t| t.measurement),
        printable.check_time.as_secs_f64(),
        write_time.as_secs_f64()
    );
    Ok(())
}

/// `kardia mesh --measure FILE`: the deviation of another mesh from the exact surface.
fn measure(
    args: &MeshArgs,
    file: &std::path::Path,
    kind: SolidKind,
    started: Instant,
) -> Result<(), String> {
    let solids = solids(args)?;
    let [solid] = &solids[..] else {
        return Err("--measure needs one surface: --equation or --preset".into());
    };
    let tolerance = args
        .tolerance
        .unwrap_or(0.01 * solid.solid.clip_radius * crate::mesh::stretch(&solid.solid.frame.m));
    let d = crate::mesh::measure_file(&solid.solid, kind, tolerance, file)
        .map_err(|e| e.to_string())?;
    outln!(
        "kardia mesh: measured {} against {} at tolerance {:.3e}: Hausdorff estimate {:.2e} \
         (mesh→surface {:.2e}, surface→mesh {:.2e} from {} surface samples, {} samples beyond \
         reach); vertices ≤ {:.2e} ({} measured, {} beyond the tolerance); time {:.2} s",
        file.display(),
        solid.name,
        tolerance,
        d.hausdorff(),
        d.mesh_to_surface,
        d.surface_to_mesh,
        d.surface_samples,
        d.beyond_reach,
        d.vertex,
        d.vertices,
        d.vertices_beyond,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
