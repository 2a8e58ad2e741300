//! The scene-file parser: one statement per line (see docs/scene-format.md), each read by
//! its row of [`STATEMENTS`] (keyword, usage line, reader) with a [`Cursor`] over the
//! line's tokens (lexer.rs, cursor.rs); surfaces by surface.rs. Every error points at the
//! part of the line that is wrong and says what was expected there.

use std::ops::Range;

use super::cursor::{parse_number, Cursor, NumberError, Source, VecArg};
use super::error::{ceil_boundary, floor_boundary};
use super::expr::Names;
use super::lexer::{Token, TokenKind};
use super::limits::{self, Limits};
use super::repeat::{self, Header};
use super::surface::{end_after_surface, is_reserved, property, surface, Materials};
use super::words::{shorten, suggest};
use super::{Animation, LoadOptions, Object, ObjectIndex, Scene, SceneError};
use crate::camera::{Camera, CameraError};
use crate::geometry::{DVec3, Frame, FrameError};
use crate::lights::Light;
use crate::materials::Material;
use crate::shapes::implicit::{preset_equation, EquationError, Implicit, PRESETS};
use crate::shapes::{
    Ellipsoid, Heart, MeshNormals, MeshShape, Parallelepiped, Plane, Polygon, Shape, ShapeError,
    Sphere,
};

type Span = Range<usize>;
type Result<T> = std::result::Result<T, SceneError>;

/// Image size used when a scene has no `SIZE` statement.
pub const DEFAULT_SIZE: (u32, u32) = (800, 600);

/// One statement: its keyword (upper case), its usage line (shown as help under errors)
/// and the reader of the rest of its line (the cursor is just after the keyword).
pub(super) struct Statement {
    /// The keyword, upper case.
    pub keyword: &'static str,
    /// How it is written.
    pub usage: &'static str,
    /// Reads the statement into the scene being built.
    pub read: fn(&mut Builder, &mut Cursor) -> Result<()>,
}

/// Every statement of the scene language.
pub(super) const STATEMENTS: &[Statement] = &[
    Statement {
        keyword: "SIZE",
        usage: "SIZE width height",
        read: Builder::size,
    },
    Statement {
        keyword: "CAMERA",
        usage: "CAMERA (eye) (look_at) (up) fov\n   or: CAMERA (eye) (look_at) (up) ORTHOGRAPHIC height",
        read: Builder::camera,
    },
    Statement {
        keyword: "BACKGROUND",
        usage: "BACKGROUND (r, g, b)",
        read: Builder::background,
    },
    Statement {
        keyword: "AMBIENT",
        usage: "AMBIENT (r, g, b)",
        read: Builder::ambient,
    },
    Statement {
        keyword: "LIGHT",
        usage: "LIGHT (position) (r, g, b) [radius [SAMPLES n]]",
        read: Builder::light,
    },
    Statement {
        keyword: "MATERIAL",
        usage: "MATERIAL name <surface>",
        read: Builder::material,
    },
    Statement {
        keyword: "SPHERE",
        usage: "SPHERE (centre) radius <surface>",
        read: Builder::sphere,
    },
    Statement {
        keyword: "PLANE",
        usage: "PLANE (point) (normal) <surface>",
        read: Builder::plane,
    },
    Statement {
        keyword: "BOX",
        usage: "BOX (corner) (edge1) (edge2) (edge3) <surface>",
        read: Builder::parallelepiped,
    },
    Statement {
        keyword: "POLYGON",
        usage: "POLYGON n (v1) (v2) … (vn) <surface>",
        read: Builder::polygon,
    },
    Statement {
        keyword: "ELLIPSOID",
        usage: "ELLIPSOID (centre) (u) (v) (w) <surface>",
        read: Builder::ellipsoid,
    },
    Statement {
        keyword: "HEART",
        usage: "HEART (position) (u) (v) (w) <surface>",
        read: Builder::heart,
    },
    Statement {
        keyword: "IMPLICIT",
        usage: "IMPLICIT \"equation\" (position) (u) (v) (w) <surface> [BOUND r]\n   \
                or: IMPLICIT preset [params…] (position) (u) (v) (w) <surface> [BOUND r]",
        read: Builder::implicit,
    },
    Statement {
        keyword: "MESH",
        usage: "MESH \"file.stl|.obj|.ply\" (position) (u) (v) (w) <surface> [SMOOTH | FLAT]",
        read: Builder::mesh,
    },
    Statement {
        keyword: "LET",
        usage: "LET name = expression",
        read: Builder::let_statement,
    },
    Statement {
        keyword: "REPEAT",
        usage: "REPEAT name FROM first TO last [STEP step]   (the lines to repeat, then END)",
        read: Builder::repeat,
    },
    Statement {
        keyword: "END",
        usage: "END   (closes the nearest open REPEAT)",
        read: Builder::end,
    },
    Statement {
        keyword: "FRAMES",
        usage: "FRAMES n [FPS f]",
        read: Builder::frames,
    },
];

/// The valid range of each preset parameter, by preset and position (presets without
/// parameters are absent).
const PRESET_PARAMETERS: &[(&str, &[Limits])] = &[
    ("torus", &[limits::LENGTH, limits::LENGTH]),
    ("kummer", &[limits::KUMMER_MU]),
    ("chmutov", &[limits::CHMUTOV_DEGREE]),
];

/// Parses scene text (the format is described in docs/scene-format.md); `name` is used in
/// error messages (usually the file path). The first mistake is returned as a
/// [`SceneError`] that points at the offending part of its line.
pub fn parse(text: &str, name: &str, options: &LoadOptions) -> Result<Scene> {
    parse_animated(text, name, options).map(|(scene, _)| scene)
}

/// As [`parse`], also returning what the scene says about its animation (`FRAMES`, `FPS`)
/// and whether any of its values depends on the time.
pub fn parse_animated(text: &str, name: &str, options: &LoadOptions) -> Result<(Scene, Animation)> {
    let src = Source { text, name };
    let mut builder = Builder {
        options: *options,
        ..Builder::default()
    };
    let mut names = Names::new(options.time);
    let last_token_end = repeat::read_lines(src, &mut builder, &mut names)?;
    builder.finish(src, last_token_end)
}

/// Reads and parses a scene file (UTF-8); a file that cannot be read is
/// [`SceneError::Unreadable`].
pub fn parse_file(path: &std::path::Path, options: &LoadOptions) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Unreadable {
        path: path.display().to_string(),
        reason: e.to_string(),
    })?;
    parse(&text, &path.display().to_string(), options)
}

/// Maps an [`EquationError`] (byte offsets within the equation text) to a span of the scene
/// text, given `inner`, the byte range of the equation between its quotes. The span always
/// lies within `inner` and on character boundaries; an error at the very end of the equation
/// (or in an empty one) becomes an empty span just before the closing quote.
pub(crate) fn equation_span(text: &str, inner: Span, e: &EquationError) -> Span {
    let inner_len = inner.end - inner.start;
    let start = inner.start + e.offset.min(inner_len);
    let end = inner.start + e.offset.saturating_add(e.len).min(inner_len);
    let start = floor_boundary(text, start).max(inner.start);
    let end = ceil_boundary(text, end.max(start)).min(inner.end);
    start..end.max(start)
}

/// The scene being assembled, statement by statement.
#[derive(Default)]
pub(super) struct Builder {
    options: LoadOptions,
    size: Option<((u32, u32), usize)>,
    camera: Option<(Camera, usize)>,
    background: Option<(DVec3, usize)>,
    ambient: Option<(DVec3, usize)>,
    lights: Vec<Light>,
    objects: Vec<Object>,
    materials: Materials,
    /// `FRAMES n [FPS f]` and its line.
    frames: Option<((u32, f64), usize)>,
    /// A `LET` just read: name, value, whether it depends on the time.
    pub(super) defined: Option<(String, f64, bool)>,
    /// A `REPEAT` just read: its loop, which the reader of the lines runs.
    pub(super) repeat: Option<Header>,
    /// Some value read so far depends on the time.
    pub(super) uses_time: bool,
}

impl Builder {
    /// One statement: finds its row of [`STATEMENTS`] and lets it read the line.
    pub(super) fn statement(&mut self, cur: &mut Cursor) -> Result<()> {
        let first = cur.peek().expect("lines without tokens are skipped");
        let word = match first.kind {
            TokenKind::Word => cur.text(&first),
            _ => return Err(cur.unexpected("a keyword at the start of the statement")),
        };
        let Some(statement) = STATEMENTS
            .iter()
            .find(|s| s.keyword.eq_ignore_ascii_case(word))
        else {
            return Err(unknown_keyword(cur, &first, word));
        };
        cur.keyword = statement.keyword;
        cur.usage = statement.usage;
        cur.pos = 1;
        (statement.read)(self, cur)
    }

    fn size(&mut self, cur: &mut Cursor) -> Result<()> {
        let (w, _) = cur.whole_in("the image width", &limits::IMAGE_SIDE)?;
        let (h, _) = cur.whole_in("the image height", &limits::IMAGE_SIDE)?;
        cur.end()?;
        once(cur, &self.size)?;
        self.size = Some(((w, h), cur.line));
        Ok(())
    }

    fn camera(&mut self, cur: &mut Cursor) -> Result<()> {
        let eye = cur.point("the eye position")?;
        let look = cur.point("the look-at point")?;
        let up = cur.direction("the up vector")?;
        let orthographic = cur
            .peek_word()
            .is_some_and(|w| w.eq_ignore_ascii_case("ORTHOGRAPHIC"));
        if orthographic {
            cur.pos += 1;
        }
        let (size, size_span) = if orthographic {
            cur.number_in("the orthographic view height", &limits::LENGTH)?
        } else {
            cur.number("the field of view in degrees")?
        };
        cur.end()?;
        let camera = if orthographic {
            Camera::orthographic(eye.v, look.v, up.v, size)
        } else {
            Camera::new(eye.v, look.v, up.v, size)
        };
        let camera = camera.map_err(|e| {
            let (span, label) = match e {
                CameraError::NotFinite => (cur.statement_span(), "not finite"),
                CameraError::NoViewDirection => (
                    Cursor::join(&eye.span, &look.span),
                    "eye and look-at are the same point",
                ),
                CameraError::BadUp => (up.span.clone(), "parallel to the view direction"),
                CameraError::BadFov(_) => (size_span.clone(), "must be in (0, 180)"),
                CameraError::BadHeight(_) => (size_span.clone(), "must be greater than 0"),
            };
            cur.fail(span, format!("degenerate camera: {e}"), label)
        })?;
        once(cur, &self.camera)?;
        self.camera = Some((camera, cur.line));
        Ok(())
    }

    fn background(&mut self, cur: &mut Cursor) -> Result<()> {
        let c = cur.colour("the background colour", &limits::COLOUR)?;
        cur.end()?;
        once(cur, &self.background)?;
        self.background = Some((c.v, cur.line));
        Ok(())
    }

    fn ambient(&mut self, cur: &mut Cursor) -> Result<()> {
        let c = cur.colour("the ambient light", &limits::COLOUR)?;
        cur.end()?;
        once(cur, &self.ambient)?;
        self.ambient = Some((c.v, cur.line));
        Ok(())
    }

    fn light(&mut self, cur: &mut Cursor) -> Result<()> {
        let position = cur.point("the light's position")?;
        let colour = cur.colour("the light's colour", &limits::INTENSITY)?;
        let radius = if cur.peek().is_some() {
            cur.number_in("the light's radius", &limits::LIGHT_RADIUS)?
                .0
        } else {
            0.0
        };
        let samples = if cur
            .peek_word()
            .is_some_and(|w| w.eq_ignore_ascii_case("SAMPLES"))
        {
            cur.pos += 1;
            cur.whole_in("the light's shadow samples", &limits::LIGHT_SAMPLES)?
                .0
        } else {
            1
        };
        cur.end()?;
        self.lights.push(Light {
            position: position.v,
            colour: colour.v,
            radius,
            samples,
        });
        Ok(())
    }

    /// `LET name = expression`: the definition is recorded once the line is read.
    fn let_statement(&mut self, cur: &mut Cursor) -> Result<()> {
        let (name, value, uses_time, _) = cur.let_definition()?;
        self.defined = Some((name, value, uses_time));
        Ok(())
    }

    /// `REPEAT name FROM first TO last [STEP step]`: the loop is recorded once the line is
    /// read, and run by `repeat::read_lines`.
    fn repeat(&mut self, cur: &mut Cursor) -> Result<()> {
        self.repeat = Some(repeat::header(cur)?);
        Ok(())
    }

    /// `END`: nothing more on the line (the reader of the lines matches it to its `REPEAT`).
    fn end(&mut self, cur: &mut Cursor) -> Result<()> {
        cur.end()
    }

    /// `FRAMES n [FPS f]`: values the same at every frame.
    fn frames(&mut self, cur: &mut Cursor) -> Result<()> {
        let (n, _) = cur.whole_in("the number of frames", &limits::FRAME_COUNT)?;
        let fps = if cur
            .peek_word()
            .is_some_and(|w| w.eq_ignore_ascii_case("FPS"))
        {
            cur.pos += 1;
            cur.number_in("the frame rate", &limits::FRAME_RATE)?.0
        } else {
            Animation::DEFAULT_FPS
        };
        cur.end()?;
        if cur.uses_time {
            return Err(cur.fail(
                cur.statement_span(),
                "FRAMES must not depend on clock, frame or frames",
                "depends on the time",
            ));
        }
        once(cur, &self.frames)?;
        self.frames = Some(((n, fps), cur.line));
        Ok(())
    }

    fn material(&mut self, cur: &mut Cursor) -> Result<()> {
        let Some(t) = cur.peek().filter(|t| t.kind == TokenKind::Word) else {
            return Err(cur.unexpected("the material's name"));
        };
        let name = cur.text(&t);
        let valid = name
            .chars()
            .next()
            .is_some_and(|c| c.is_alphabetic() || c == '_')
            && name
                .chars()
                .all(|c| c.is_alphanumeric() || c == '_' || c == '-');
        if !valid {
            return Err(cur.fail(
                t.span,
                format!(
                    "`{}` is not a valid material name: names start with a letter or `_` and \
                     contain only letters, digits, `_` and `-`",
                    shorten(name, 30)
                ),
                "invalid name",
            ));
        }
        if is_reserved(name) {
            return Err(cur.fail(
                t.span,
                format!("`{name}` is a surface-property keyword and cannot name a material"),
                "reserved word",
            ));
        }
        if let Some((_, line)) = self.materials.get(name) {
            return Err(cur.fail(
                t.span,
                format!("material `{name}` is already defined on line {line}"),
                "defined twice",
            ));
        }
        cur.pos += 1;
        let m = surface(cur, &self.materials)?;
        end_after_surface(cur)?;
        self.materials.insert(name.to_string(), (m, cur.line));
        Ok(())
    }

    /// Adds the object the current statement describes.
    fn add(&mut self, cur: &Cursor, shape: Box<dyn Shape>, material: Material) -> Result<()> {
        self.objects
            .push(Object::new(shape, material, cur.keyword, cur.line));
        Ok(())
    }

    fn sphere(&mut self, cur: &mut Cursor) -> Result<()> {
        let c = cur.point("the sphere's centre")?;
        let (r, _) = cur.number_in("the sphere's radius", &limits::LENGTH)?;
        let m = surface(cur, &self.materials)?;
        end_after_surface(cur)?;
        let keyword = cur.statement_keyword_span();
        let s = Sphere::new(c.v, r).map_err(|e| shape_error(cur, keyword, e))?;
        self.add(cur, Box::new(s), m)
    }

    fn plane(&mut self, cur: &mut Cursor) -> Result<()> {
        let p = cur.point("a point on the plane")?;
        let n = cur.direction("the plane's normal")?;
        let m = surface(cur, &self.materials)?;
        end_after_surface(cur)?;
        let s = Plane::new(p.v, n.v).map_err(|e| shape_error(cur, n.span.clone(), e))?;
        self.add(cur, Box::new(s), m)
    }

    fn polygon(&mut self, cur: &mut Cursor) -> Result<()> {
        let (count, count_span) = cur.number("the number of vertices")?;
        if !(count.fract() == 0.0 && count >= 3.0) {
            return Err(cur.fail(
                count_span,
                format!("a polygon needs a whole number of at least 3 vertices, not {count}"),
                "must be a whole number ≥ 3",
            ));
        }
        cur.check(
            count,
            &count_span,
            "the number of vertices",
            &limits::POLYGON_VERTICES,
        )?;
        let n = count as u32;
        let mut verts = Vec::new();
        for k in 1..=n {
            let what = format!("vertex {k} of {n}");
            if cur.peek_kind() != Some(TokenKind::Open) {
                return Err(cur.fail(
                    cur.here(),
                    format!(
                        "expected {what}, a vector (x, y, z), found {}: the polygon \
                         was declared with {n} vertices",
                        cur.describe(cur.peek().as_ref())
                    ),
                    format!("expected {what}"),
                ));
            }
            verts.push(cur.point(&what)?);
        }
        let m = surface(cur, &self.materials)?;
        end_after_surface(cur)?;
        let s = Polygon::new(verts.iter().map(|a| a.v).collect()).map_err(|e| {
            // Point at the vertex the message names, else at all of them.
            let span = match vertex_named_in(&e.0, verts.len()) {
                Some(k) => verts[k - 1].span.clone(),
                None => Cursor::join(&verts[0].span, &verts[verts.len() - 1].span),
            };
            shape_error(cur, span, e)
        })?;
        self.add(cur, Box::new(s), m)
    }

    /// The position, basis and surface of a basis-placed shape, with its frame checked;
    /// the span returned covers the basis vectors.
    fn placed(
        &self,
        cur: &mut Cursor,
        origin: &str,
        names: [&str; 3],
    ) -> Result<([DVec3; 4], Span, Material, Frame)> {
        let p = cur.point(origin)?;
        let (u, v, w) = basis(cur, names)?;
        let m = surface(cur, &self.materials)?;
        end_after_surface(cur)?;
        let frame = check_frame(cur, &p, [&u, &v, &w], names)?;
        Ok((
            [p.v, u.v, v.v, w.v],
            Cursor::join(&u.span, &w.span),
            m,
            frame,
        ))
    }

    fn parallelepiped(&mut self, cur: &mut Cursor) -> Result<()> {
        let names = ["edge1", "edge2", "edge3"];
        let ([p, u, v, w], span, m, _) = self.placed(cur, "the box's corner", names)?;
        let s = Parallelepiped::new(p, u, v, w).map_err(|e| shape_error(cur, span, e))?;
        self.add(cur, Box::new(s), m)
    }

    fn ellipsoid(&mut self, cur: &mut Cursor) -> Result<()> {
        let names = ["u", "v", "w"];
        let ([p, u, v, w], span, m, _) = self.placed(cur, "the ellipsoid's centre", names)?;
        let s = Ellipsoid::new(p, u, v, w).map_err(|e| shape_error(cur, span, e))?;
        self.add(cur, Box::new(s), m)
    }

    fn heart(&mut self, cur: &mut Cursor) -> Result<()> {
        let names = ["u", "v", "w"];
        // The frame checked with the numbers, not made again from them.
        let (_, _, m, frame) = self.placed(cur, "the heart's position", names)?;
        let s = Heart::from_frame(frame).with_solver(self.options.solver);
        self.add(cur, Box::new(s), m)
    }

    fn implicit(&mut self, cur: &mut Cursor) -> Result<()> {
        enum EquationSource {
            Quoted(Span),
            Preset(Span),
        }
        let Some(t) = cur.peek() else {
            return Err(cur.unexpected("an equation in quotes or a preset name"));
        };
        let (equation, source) = match t.kind {
            TokenKind::Str => {
                cur.pos += 1;
                let inner = t.inner();
                (
                    cur.src.text[inner.clone()].to_string(),
                    EquationSource::Quoted(inner),
                )
            }
            TokenKind::Word if parse_number(cur.text(&t)) == Err(NumberError::NotANumber) => {
                let word = cur.text(&t);
                let lower = word.to_ascii_lowercase();
                let Some(&(name, count)) = PRESETS.iter().find(|p| p.0 == lower) else {
                    let names: Vec<&str> = PRESETS.iter().map(|p| p.0).collect();
                    let help = match suggest(word, names.iter().copied()) {
                        Some(s) => format!("did you mean `{s}`? presets: {}", names.join(", ")),
                        None => format!(
                            "presets: {}; or write an equation in quotes",
                            names.join(", ")
                        ),
                    };
                    return Err(cur.fail_help(
                        t.span,
                        format!("unknown implicit-surface preset `{}`", shorten(word, 30)),
                        "unknown preset",
                        help,
                    ));
                };
                cur.pos += 1;
                let mut params = Vec::new();
                let mut spans = Vec::new();
                let mut last = t.span.clone();
                while cur.peek_kind() == Some(TokenKind::Word) {
                    let (x, span) =
                        cur.number(&format!("parameter {} of {name}", params.len() + 1))?;
                    if params.len() == count {
                        return Err(cur.fail(
                            span,
                            format!(
                                "too many parameters: the preset {name} takes {count}, not {}",
                                params.len() + 1
                            ),
                            "extra parameter",
                        ));
                    }
                    params.push(x);
                    spans.push(span.clone());
                    last = span;
                }
                if params.len() < count {
                    return Err(cur.fail(
                        cur.here(),
                        format!(
                            "expected parameter {} of {name}, found {}: the preset {name} takes {count}",
                            params.len() + 1,
                            cur.describe(cur.peek().as_ref())
                        ),
                        "missing parameter",
                    ));
                }
                let ranges = PRESET_PARAMETERS
                    .iter()
                    .find(|p| p.0 == name)
                    .map_or(&[][..], |p| p.1);
                for (k, (&x, limits)) in params.iter().zip(ranges).enumerate() {
                    let what = format!("parameter {} of {name}", k + 1);
                    cur.check(x, &spans[k], &what, limits)?;
                }
                let span = t.span.start..last.end;
                let eq = preset_equation(name, &params).map_err(|m| {
                    cur.fail(
                        span.clone(),
                        format!("preset {name}: {m}"),
                        "invalid preset",
                    )
                })?;
                (eq, EquationSource::Preset(span))
            }
            _ => return Err(cur.unexpected("an equation in quotes or a preset name")),
        };
        let p = cur.point("the surface's position")?;
        let names = ["u", "v", "w"];
        let (u, v, w) = basis(cur, names)?;
        let m = surface(cur, &self.materials)?;
        let mut bound = None;
        if cur
            .peek_word()
            .is_some_and(|w| w.eq_ignore_ascii_case("BOUND"))
        {
            cur.pos += 1;
            bound = Some(cur.number_in("the bounding radius", &limits::LENGTH)?.0);
            cur.end()?;
        } else {
            end_after_surface(cur)?;
        }
        let frame = check_frame(cur, &p, [&u, &v, &w], names)?;
        let equation_uses_time = std::cell::Cell::new(false);
        let constants = |name: &str| {
            let (value, uses_time) = cur.names.value(name)?;
            equation_uses_time.set(equation_uses_time.get() | uses_time);
            Some(value)
        };
        let shape = Implicit::with_constants(&equation, &constants, frame, bound);
        cur.uses_time |= equation_uses_time.get();
        let shape = shape.map_err(|e| match &source {
            EquationSource::Quoted(inner) => cur.fail(
                equation_span(cur.src.text, inner.clone(), &e),
                format!("invalid equation: {e}"),
                "here",
            ),
            EquationSource::Preset(span) => cur.fail(
                span.clone(),
                format!("this preset gives no usable surface with these parameters: {e}"),
                "invalid preset",
            ),
        })?;
        self.add(cur, Box::new(shape.with_solver(self.options.solver)), m)
    }

    /// `MESH "file" (position) (u) (v) (w) <surface> [SMOOTH | FLAT]`: a triangle mesh read
    /// from a file (a relative path is taken from the scene file's folder).
    fn mesh(&mut self, cur: &mut Cursor) -> Result<()> {
        let Some(t) = cur.peek().filter(|t| t.kind == TokenKind::Str) else {
            return Err(cur.unexpected("the mesh file's name in quotes"));
        };
        if self.options.forbid_files {
            return Err(cur.fail_help(
                t.span.clone(),
                "MESH reads a file, which a scene here may not do",
                "a file is named here",
                "render a scene with MESH with `kardia render`",
            ));
        }
        cur.pos += 1;
        let file = cur.src.text[t.inner()].to_string();
        let p = cur.point("the mesh's position")?;
        let names = ["u", "v", "w"];
        let (u, v, w) = basis(cur, names)?;
        let m = surface(cur, &self.materials)?;
        let mut normals = MeshNormals::default();
        if let Some(word) = cur.peek_word() {
            if word.eq_ignore_ascii_case("FLAT") || word.eq_ignore_ascii_case("SMOOTH") {
                normals = if word.eq_ignore_ascii_case("FLAT") {
                    MeshNormals::Flat
                } else {
                    MeshNormals::Smooth
                };
                cur.pos += 1;
                cur.end()?;
            }
        }
        end_after_surface(cur)?;
        check_frame(cur, &p, [&u, &v, &w], names)?;
        let path = mesh_path(cur.src.name, &file);
        let shape = MeshShape::from_file(&path, [p.v, u.v, v.v, w.v], normals)
            .map_err(|e| shape_error(cur, t.span.clone(), e))?;
        self.add(cur, Box::new(shape), m)
    }

    /// The scene; `end` is where the last statement ends (for a missing-camera error).
    fn finish(self, src: Source, end: usize) -> Result<(Scene, Animation)> {
        let Some((camera, _)) = self.camera else {
            return Err(src.error(
                end..end,
                "the scene has no CAMERA",
                "expected a CAMERA statement somewhere in the scene",
                Some("add a line such as `CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 40`".into()),
            ));
        };
        let (width, height) = self.size.map_or(DEFAULT_SIZE, |s| s.0);
        let animation = Animation {
            frames: self.frames.map(|f| f.0 .0),
            fps: self.frames.map_or(Animation::DEFAULT_FPS, |f| f.0 .1),
            uses_time: self.uses_time,
        };
        let scene = Scene {
            width,
            height,
            camera,
            background: self.background.map_or(DVec3::ZERO, |b| b.0),
            ambient: self.ambient.map_or(DVec3::ZERO, |a| a.0),
            lights: self.lights,
            index: ObjectIndex::of(&self.objects),
            objects: self.objects,
        };
        Ok((scene, animation))
    }
}
/// Where the `MESH` file `file` named in the scene `scene_name` is: a relative path is taken
/// from the folder of the scene file when `scene_name` names one, else from the current
/// folder.
fn mesh_path(scene_name: &str, file: &str) -> std::path::PathBuf {
    let path = std::path::Path::new(file);
    let scene = std::path::Path::new(scene_name);
    match scene.parent() {
        Some(folder) if path.is_relative() && scene.is_file() => folder.join(path),
        _ => path.to_path_buf(),
    }
}

/// An error about an invalid shape of the current statement, at `span`.
fn shape_error(cur: &Cursor, span: Span, e: ShapeError) -> SceneError {
    cur.fail(
        span,
        format!("invalid {}: {e}", cur.keyword.to_ascii_lowercase()),
        "invalid shape",
    )
}

/// Fails when a once-only statement was already given.
fn once<T>(cur: &Cursor, slot: &Option<(T, usize)>) -> Result<()> {
    let keyword = cur.keyword;
    match slot {
        None => Ok(()),
        Some((_, line)) => Err(cur.fail_help(
            cur.statement_keyword_span(),
            format!("{keyword} is given twice (first on line {line})"),
            "repeated statement",
            format!("a scene has at most one {keyword}; remove one of them"),
        )),
    }
}

/// The three non-zero basis vectors of a placed shape.
fn basis(cur: &mut Cursor, names: [&str; 3]) -> Result<(VecArg, VecArg, VecArg)> {
    let u = cur.direction(format_args!("the basis vector {}", names[0]))?;
    let v = cur.direction(format_args!("the basis vector {}", names[1]))?;
    let w = cur.direction(format_args!("the basis vector {}", names[2]))?;
    Ok((u, v, w))
}

/// The frame of a placed shape, or an error spanning the basis vectors.
fn check_frame(cur: &Cursor, p: &VecArg, b: [&VecArg; 3], names: [&str; 3]) -> Result<Frame> {
    Frame::new(p.v, b[0].v, b[1].v, b[2].v).map_err(|e| {
        let span = Cursor::join(&b[0].span, &b[2].span);
        match e {
            FrameError::Singular => cur.fail(
                span,
                format!(
                    "{}, {} and {} are linearly dependent (or nearly so), so the shape would be flat",
                    names[0], names[1], names[2]
                ),
                "linearly dependent",
            ),
            FrameError::NotFinite => cur.fail(span, e.to_string(), "not finite"),
        }
    })
}

/// The 1-based vertex number a polygon error message names (`"… vertex 4 …"`), if it is one
/// of the `count` vertices.
fn vertex_named_in(message: &str, count: usize) -> Option<usize> {
    let rest = &message[message.find("vertex ")? + "vertex ".len()..];
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok().filter(|&k| (1..=count).contains(&k))
}
/// The error for a statement starting with an unknown word.
fn unknown_keyword(cur: &Cursor, t: &Token, word: &str) -> SceneError {
    let span = t.span.clone();
    if let Some(p) = property(word) {
        return cur.fail_help(
            span,
            format!("{} is a surface property, not a statement", p.keyword),
            "not a statement",
            "surface properties follow an object's colour on the same line, e.g. \
             `SPHERE (0, 0, 0) 1 (0.8, 0.1, 0.1) SPECULAR 0.5 40`",
        );
    }
    let names = STATEMENTS.iter().map(|s| s.keyword);
    let help = match suggest(word, names.clone()) {
        Some(s) => format!("did you mean {s}?"),
        None => format!("keywords: {}", names.collect::<Vec<_>>().join(", ")),
    };
    if parse_number(word) != Err(NumberError::NotANumber) {
        return cur.fail_help(
            span,
            format!(
                "expected a keyword at the start of the statement, found the number `{}`",
                shorten(word, 30)
            ),
            "expected a keyword",
            help,
        );
    }
    cur.fail_help(
        span,
        format!("unknown keyword `{}`", shorten(word, 30)),
        "unknown keyword",
        help,
    )
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scene_that_may_read_no_file_refuses_mesh() {
        let text = "CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 30\n\
                    MESH \"no-such-file.stl\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (1, 0, 0)\n";
        let forbidden = LoadOptions {
            forbid_files: true,
            ..LoadOptions::default()
        };
        let err = crate::scene::parse(text, "t.scene", &forbidden).expect_err("MESH refused");
        let shown = format!("{err:?}");
        assert!(shown.contains("MESH reads a file"), "{shown}");
        // Allowed, the same text gets as far as opening the file.
        let err = crate::scene::parse(text, "t.scene", &LoadOptions::default())
            .expect_err("the file is missing");
        let shown = format!("{err:?}");
        assert!(!shown.contains("MESH reads a file"), "{shown}");
        assert!(shown.contains("no-such-file.stl"), "{shown}");
    }

    #[test]
    fn vertex_numbers_in_polygon_messages() {
        assert_eq!(vertex_named_in("vertex 4 is 0.5 units off", 5), Some(4));
        assert_eq!(
            vertex_named_in("the polygon's vertex 12 is bad", 12),
            Some(12)
        );
        assert_eq!(vertex_named_in("vertex 6 is bad", 5), None);
        assert_eq!(vertex_named_in("no area", 5), None);
        assert_eq!(vertex_named_in("vertex x", 5), None);
    }

    fn eq_error(offset: usize, len: usize) -> EquationError {
        EquationError {
            offset,
            len,
            message: "bad".into(),
        }
    }

    #[test]
    fn equation_errors_map_inside_the_quotes() {
        let text = "IMPLICIT \"x^2 + y^2 = 1\" (0,0,0)";
        let inner = 10..23;
        assert_eq!(&text[inner.clone()], "x^2 + y^2 = 1");
        // `+` at offset 4.
        assert_eq!(equation_span(text, inner.clone(), &eq_error(4, 1)), 14..15);
        assert_eq!(&text[14..15], "+");
        // Past the end: clamped to an empty span before the closing quote.
        assert_eq!(equation_span(text, inner.clone(), &eq_error(13, 0)), 23..23);
        assert_eq!(equation_span(text, inner.clone(), &eq_error(99, 5)), 23..23);
        // A length running past the end is cut at the closing quote.
        assert_eq!(
            equation_span(text, inner.clone(), &eq_error(10, 50)),
            20..23
        );
        assert_eq!(
            equation_span(text, inner, &eq_error(usize::MAX, usize::MAX)),
            23..23
        );
    }

    #[test]
    fn equation_error_spans_respect_character_boundaries() {
        let text = "IMPLICIT \"xé+y\"";
        let inner = 10..15;
        assert_eq!(&text[inner.clone()], "xé+y");
        // Offset 2 is inside `é` (bytes 1..3): widened to the whole character.
        let s = equation_span(text, inner.clone(), &eq_error(2, 1));
        assert_eq!(&text[s], "é");
        let s = equation_span(text, inner, &eq_error(1, 1));
        assert_eq!(&text[s], "é");
    }

    #[test]
    fn full_scene_error_points_inside_the_equation() {
        // Unit-tests the mapping through a SceneError as the parser builds it.
        let text = "IMPLICIT \"x^2 + y^2 = 1\" (0,0,0)";
        let src = Source { text, name: "t" };
        let span = equation_span(text, 10..23, &eq_error(4, 1));
        let e = src.error(span, "invalid equation: bad", "here", None);
        assert_eq!(e.location(), Some((1, 15)));
    }
}
