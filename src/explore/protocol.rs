//! The messages between the page and the server (one WebSocket per page).
//!
//! The page sends JSON text messages ([`ClientMessage`]). The server answers with JSON text
//! messages ([`ServerMessage`]) and with binary messages for images: a little-endian `u32`
//! header length, that many bytes of JSON header ([`FrameHeader`]), then the payload (raw
//! RGBA8 pixels, row-major from the top-left, for a frame; the file's bytes for a PNG).

use crate::scene::SceneError;
use serde::{Deserialize, Serialize};

/// What the page asks for.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMessage {
    /// Show this scene text at this size: starts a progressive render, cancelling the one in
    /// flight. `seq` is echoed in every frame and error it causes.
    View {
        /// Page-chosen number of this request; frames of older requests are never sent after it.
        seq: u64,
        /// The whole scene text (its CAMERA is the view's camera).
        scene: String,
        /// View width in pixels.
        width: u32,
        /// View height in pixels.
        height: u32,
        /// Which image: a name of `kardia render --view` (default `shaded`).
        #[serde(default)]
        view: Option<String>,
    },
    /// The expanded equation and default clip radius of a preset with its parameters.
    Preset {
        /// Scene-language preset name.
        name: String,
        /// Its parameters.
        params: Vec<f64>,
    },
    /// The page is hidden: stop refining its view (the pass in flight is cancelled) until
    /// it sends a view again.
    Pause {},
    /// What the root finder did for the camera ray through the centre of pixel `(x, y)`
    /// (`(0, 0)` the top-left pixel) of this scene's view at this size; answered with a
    /// `probe` message.
    Probe {
        /// Echoed in the reply.
        seq: u64,
        /// The whole scene text (its CAMERA is the view's camera).
        scene: String,
        /// View width in pixels.
        width: u32,
        /// View height in pixels.
        height: u32,
        /// Pixel column, 0 ..= width − 1.
        x: u32,
        /// Pixel row from the top, 0 ..= height − 1.
        y: u32,
    },
    /// Mesh this scene as `kardia mesh` does (its HEART and IMPLICIT objects) and send the
    /// file: `format` is `"stl"` or `"3mf"`.
    Mesh {
        /// Echoed in the reply.
        seq: u64,
        /// The whole scene text.
        scene: String,
        /// `"stl"` or `"3mf"`.
        format: String,
    },
    /// Stop the save in flight (its reply is then an error saying it was cancelled); nothing
    /// when none is rendering.
    CancelSave {},
    /// Stop the mesh in flight (its reply is then an error saying it was cancelled); nothing
    /// when none is being made.
    CancelMesh {},
    /// Render this scene once at this size and samples, and send it as a PNG.
    Save {
        /// Echoed in the reply.
        seq: u64,
        /// The whole scene text.
        scene: String,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
        /// Samples per pixel.
        spp: u32,
        /// Which image: a name of `kardia render --view` (default `shaded`).
        #[serde(default)]
        view: Option<String>,
        /// A transparent background: an RGBA PNG, as `kardia render --alpha` (default false).
        #[serde(default)]
        alpha: bool,
    },
}

/// The render view named `name` (`None`: shaded), or a message listing the names.
pub fn view_named(name: Option<&str>) -> Result<crate::pipeline::View, String> {
    use crate::pipeline::View;
    let Some(name) = name else {
        return Ok(View::Shaded);
    };
    View::ALL
        .iter()
        .find(|(_, n)| *n == name)
        .map(|(v, _)| *v)
        .ok_or_else(|| {
            let names: Vec<_> = View::ALL.iter().map(|(_, n)| *n).collect();
            format!(
                "unknown view '{}': one of {}",
                name.chars().take(40).collect::<String>(),
                names.join(", ")
            )
        })
}

/// A scene that did not parse, located in its text.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SceneProblem {
    /// The one-line form `file:line:column: message`, as `kardia render` prints first.
    pub message: String,
    /// The full report `kardia render` prints (source line with a caret), without colours.
    pub report: String,
    /// 1-based line of the problem.
    pub line: usize,
    /// 1-based column (in characters) of the problem.
    pub column: usize,
    /// Length of the marked part, in characters (0 for a point).
    pub length: usize,
}

impl SceneProblem {
    /// The problem of a scene error about `text`.
    pub fn new(error: &SceneError, text: &str) -> Self {
        let mut report = String::new();
        let handler =
            miette::GraphicalReportHandler::new_themed(miette::GraphicalTheme::unicode_nocolor())
                .with_width(100);
        if handler.render_report(&mut report, error).is_err() {
            report = error.to_string();
        }
        let (line, column) = error.location().unwrap_or((1, 1));
        let length = match error {
            SceneError::Invalid(e) => {
                let start = e.span.offset().min(text.len());
                let end = (start + e.span.len()).min(text.len());
                text.get(start..end).map_or(0, |s| s.chars().count())
            }
            SceneError::Unreadable { .. } => 0,
        };
        Self {
            message: error.to_string(),
            report,
            line,
            column,
            length,
        }
    }
}

/// What the server says in text messages.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    /// First message on every connection.
    Hello {
        /// kardia's version.
        version: &'static str,
        /// The limits this server enforces.
        limits: super::Limits,
        /// The equation-mode gallery.
        presets: Vec<super::gallery::GalleryPreset>,
        /// The scene files that can be opened, `(name, text)`.
        scenes: Vec<(&'static str, &'static str)>,
        /// The scene the server was started with: `(name, text)`.
        initial: (String, String),
        /// The names of the views a page may ask for (`shaded` first).
        views: Vec<&'static str>,
        /// How to read each study view's colours (every view but `shaded`).
        legends: Vec<ViewLegend>,
        /// Where the page starts: `"equation"` (on the heart) when the server was started
        /// without a scene, `"scene"` (on `initial`) when it was given one.
        start_mode: &'static str,
    },
    /// Where the surfaces of request `seq`'s scene lie, found when the scene was loaded
    /// (each object's world-space box, as the renderer bounds it): the page frames the view
    /// on it ("Fit"). Sent once per scene text, not for a change of camera alone.
    Extent {
        /// The request.
        seq: u64,
        /// Lower corner of the box holding every object, world units.
        min: [f64; 3],
        /// Upper corner, world units.
        max: [f64; 3],
    },
    /// The scene of request `seq` did not parse; the last good image stays.
    SceneError {
        /// The request.
        seq: u64,
        /// Where and what.
        problem: SceneProblem,
    },
    /// A preset's expansion.
    Preset {
        /// Preset name.
        name: String,
        /// Its parameters.
        params: Vec<f64>,
        /// Its equation, as the scene language expands it.
        equation: String,
        /// Its default clip radius.
        bound: f64,
    },
    /// What the root finder did for the pixel of probe request `seq`.
    Probe {
        /// The probe request.
        seq: u64,
        /// Its pixel column.
        x: u32,
        /// Its pixel row.
        y: u32,
        /// The report of the nearest polynomial surface the ray hits, else of the first whose
        /// root finder it reaches; `None` when it reaches none (the study views' black).
        report: Option<ProbeReport>,
    },
    /// How far the save of request `seq` has got (about every quarter second while it
    /// renders).
    SaveProgress {
        /// The save request.
        seq: u64,
        /// Pixels finished.
        done: u64,
        /// Pixels of the image.
        total: u64,
    },
    /// How far the mesh of request `seq` has got (about every quarter second).
    MeshProgress {
        /// The mesh request.
        seq: u64,
        /// 0 to 1.
        fraction: f64,
    },
    /// A request that was refused (malformed, too large, over a limit), or a failure.
    Error {
        /// The request it answers, when known.
        seq: Option<u64>,
        /// What was wrong, for the page to show.
        message: String,
    },
}

/// What the root finder did for one camera ray (a [`crate::shapes::SolverReport`] with its
/// names spelled out as the study views' legends spell them).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ProbeReport {
    /// Whether the ray hits the surface.
    pub hit: bool,
    /// The ray parameter of the hit (world units along the unit camera ray), if any.
    pub t: Option<f64>,
    /// Distinct real roots of the ray's polynomial in the interval searched (the `roots`
    /// view's count).
    pub roots: u32,
    /// Degree of the ray's polynomial.
    pub degree: u32,
    /// The method that settled the first root or proved there is none: the `path` view's
    /// legend entry for this pixel.
    pub settled_by: &'static str,
    /// Refinement steps over all of the ray's queries (the `iterations` view's count).
    pub refine_steps: u32,
    /// Isolation steps (splits) over all of the ray's queries.
    pub splits: u32,
    /// First-root queries made.
    pub queries: u32,
    /// `|∇f|` at the hit, object space (the `conditioning` view's value); `None` for a miss.
    pub gradient_norm: Option<f64>,
}

impl ProbeReport {
    /// The report of `scene`'s camera ray through the centre of pixel `(x, y)` of a
    /// `width × height` view through `camera`; `None` when the ray reaches no root finder.
    pub fn of_pixel(
        scene: &crate::scene::Scene,
        camera: &crate::camera::Camera,
        (width, height): (u32, u32),
        (x, y): (u32, u32),
    ) -> Option<Self> {
        let ray = camera.ray(f64::from(x) + 0.5, f64::from(y) + 0.5, width, height);
        let report = crate::integrator::solver_view::primary_report(scene, &ray)?;
        Some(Self {
            hit: report.hit.is_some(),
            t: report.hit,
            roots: report.distinct_roots,
            degree: report.degree,
            settled_by: report.settled_by.name(),
            refine_steps: report.trace.refine_steps,
            splits: report.trace.splits,
            queries: report.trace.queries,
            gradient_norm: report.gradient_norm,
        })
    }
}

/// A view's legend as the page shows it (see [`crate::integrator::Legend`]).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ViewLegend {
    /// The view's name.
    pub view: &'static str,
    /// What the view shows.
    pub title: &'static str,
    /// `(meaning, "#rrggbb")` in order: the colour as the view's PNG shows it.
    pub swatches: Vec<(String, String)>,
    /// Anything else to know (misses); may be empty.
    pub note: &'static str,
}

/// The legends of every study view, in [`crate::pipeline::View::ALL`] order.
pub fn view_legends() -> Vec<ViewLegend> {
    crate::pipeline::View::ALL
        .iter()
        .filter_map(|&(view, name)| {
            let legend = view.legend()?;
            Some(ViewLegend {
                view: name,
                title: legend.title,
                swatches: legend
                    .swatches
                    .into_iter()
                    .map(|s| {
                        let [r, g, b] = s.srgb;
                        (s.label, format!("#{r:02x}{g:02x}{b:02x}"))
                    })
                    .collect(),
                note: legend.note,
            })
        })
        .collect()
}

impl ServerMessage {
    /// The message as JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| {
            format!(r#"{{"type":"error","seq":null,"message":"cannot encode a reply: {e}"}}"#)
        })
    }
}

/// Header of a binary message.
#[derive(Debug, Clone, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum FrameHeader {
    /// A frame of a progressive render; payload: `width·height·4` bytes of RGBA8 (sRGB).
    Frame {
        /// The request it belongs to.
        seq: u64,
        /// Frame width in pixels (may be below the view's for the coarse passes).
        width: u32,
        /// Frame height in pixels.
        height: u32,
        /// The view's width in pixels.
        view_width: u32,
        /// The view's height in pixels.
        view_height: u32,
        /// Samples per pixel accumulated in this frame.
        spp: u32,
        /// 0-based pass number of this request.
        pass: u32,
        /// Wall time of this pass's render, milliseconds.
        ms: f64,
        /// Rays traced in this pass.
        rays: u64,
        /// Whether this is the last frame of the request (the samples limit is reached).
        done: bool,
    },
    /// A mesh file; payload: its bytes, as `kardia mesh` writes them.
    Mesh {
        /// The request it answers.
        seq: u64,
        /// `"stl"` or `"3mf"`.
        format: String,
        /// Triangles in the mesh.
        triangles: usize,
        /// Wall time of the meshing, milliseconds.
        ms: f64,
    },
    /// A saved image; payload: the PNG file.
    Png {
        /// The request it answers.
        seq: u64,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
        /// Samples per pixel.
        spp: u32,
        /// Wall time of the render, milliseconds.
        ms: f64,
    },
}

/// A binary message: header length, header, payload.
pub fn binary(header: &FrameHeader, payload: &[u8]) -> Vec<u8> {
    let head = serde_json::to_vec(header).unwrap_or_default();
    let mut out = Vec::with_capacity(4 + head.len() + payload.len());
    out.extend_from_slice(&(head.len() as u32).to_le_bytes());
    out.extend_from_slice(&head);
    out.extend_from_slice(payload);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_message_reads_and_unknown_fields_are_refused() {
        let m: ClientMessage = serde_json::from_str(
            r#"{"type":"view","seq":3,"scene":"CAMERA (1,0,0) (0,0,0) (0,0,1) 40","width":8,"height":6}"#,
        )
        .unwrap();
        assert!(matches!(
            m,
            ClientMessage::View {
                seq: 3,
                width: 8,
                ..
            }
        ));
        assert!(serde_json::from_str::<ClientMessage>(r#"{"type":"view","seq":1}"#).is_err());
        assert!(serde_json::from_str::<ClientMessage>(
            r#"{"type":"preset","name":"torus","params":[1,0.3],"path":"/etc/passwd"}"#
        )
        .is_err());
        assert!(serde_json::from_str::<ClientMessage>(r#"{"type":"open_file"}"#).is_err());
        assert_eq!(
            serde_json::from_str::<ClientMessage>(r#"{"type":"pause"}"#).unwrap(),
            ClientMessage::Pause {}
        );
        assert!(serde_json::from_str::<ClientMessage>(r#"{"type":"pause","x":1}"#).is_err());
    }

    #[test]
    fn views_by_name() {
        use crate::pipeline::View;
        assert_eq!(view_named(None), Ok(View::Shaded));
        assert_eq!(view_named(Some("normals")), Ok(View::Normals));
        let e = view_named(Some("nonsense")).unwrap_err();
        assert!(e.contains("one of shaded, normals, depth"), "{e}");
    }

    #[test]
    fn binary_layout() {
        let h = FrameHeader::Png {
            seq: 1,
            width: 2,
            height: 3,
            spp: 4,
            ms: 5.0,
        };
        let b = binary(&h, &[9, 9]);
        let n = u32::from_le_bytes(b[..4].try_into().unwrap()) as usize;
        let head: serde_json::Value = serde_json::from_slice(&b[4..4 + n]).unwrap();
        assert_eq!(head["type"], "png");
        assert_eq!(&b[4 + n..], &[9, 9]);
    }

    #[test]
    fn scene_problem_locates_the_error() {
        let text = "CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 40\nSPHERE (0,0,0) -1 (1,1,1)\n";
        let err = crate::scene::parse(text, "page.scene", &Default::default()).unwrap_err();
        let p = SceneProblem::new(&err, text);
        assert_eq!((p.line, p.column, p.length), (2, 16, 2));
        assert!(p.message.starts_with("page.scene:2:16: "), "{}", p.message);
        assert!(p.report.contains("SPHERE (0,0,0) -1"), "{}", p.report);
    }

    #[test]
    fn hello_carries_a_legend_for_every_study_view() {
        let legends = view_legends();
        let names: Vec<_> = legends.iter().map(|l| l.view).collect();
        let study: Vec<_> = crate::pipeline::View::ALL
            .iter()
            .map(|(_, n)| *n)
            .filter(|n| *n != "shaded")
            .collect();
        assert_eq!(names, study);
        for l in &legends {
            assert!(l.swatches.iter().all(|(label, c)| !label.is_empty()
                && c.len() == 7
                && c.starts_with('#')
                && c[1..].chars().all(|d| d.is_ascii_hexdigit())));
        }
        let json = serde_json::to_string(&legends[0]).unwrap();
        assert!(json.contains(r##""swatches":[["##), "{json}");
    }
}
