//! The scene-file parser: one statement per line (see docs/scene-format.md), each read by
//! a [`Cursor`] over the line's tokens (lexer.rs, cursor.rs). Every error
//! points at the part of the line that is wrong and says what was expected there.

use std::collections::HashMap;
use std::ops::Range;

use super::cursor::{parse_number, shorten, suggest, Cursor, NumberError, Source, VecArg};
use super::error::{ceil_boundary, floor_boundary};
use super::expr::{self, Names};
use super::lexer::{lex_line, Token, TokenKind};
use super::{Animation, LoadOptions, Object, Scene, SceneError};
use crate::camera::{Camera, CameraError};
use crate::geometry::{DVec3, Frame, FrameError};
use crate::lights::Light;
use crate::materials::Material;
use crate::shapes::implicit::{preset_equation, EquationError, Implicit, PRESETS};
use crate::shapes::{Ellipsoid, Heart, Parallelepiped, Plane, Polygon, Shape, ShapeError, Sphere};

type Span = Range<usize>;
type Result<T> = std::result::Result<T, SceneError>;

/// Image size used when a scene has no `SIZE` statement.
pub const DEFAULT_SIZE: (u32, u32) = (800, 600);

/// Every statement keyword with its usage line (shown as help under errors).
pub(crate) const STATEMENTS: &[(&str, &str)] = &[
    ("SIZE", "SIZE width height"),
    ("CAMERA", "CAMERA (eye) (look_at) (up) fov"),
    ("BACKGROUND", "BACKGROUND (r, g, b)"),
    ("AMBIENT", "AMBIENT (r, g, b)"),
    ("LIGHT", "LIGHT (position) (r, g, b) [radius [SAMPLES n]]"),
    ("MATERIAL", "MATERIAL name <surface>"),
    ("SPHERE", "SPHERE (centre) radius <surface>"),
    ("PLANE", "PLANE (point) (normal) <surface>"),
    ("BOX", "BOX (corner) (edge1) (edge2) (edge3) <surface>"),
    ("POLYGON", "POLYGON n (v1) (v2) … (vn) <surface>"),
    ("ELLIPSOID", "ELLIPSOID (centre) (u) (v) (w) <surface>"),
    ("HEART", "HEART (position) (u) (v) (w) <surface>"),
    (
        "IMPLICIT",
        "IMPLICIT \"equation\" (position) (u) (v) (w) <surface> [BOUND r]\n   \
         or: IMPLICIT preset [params…] (position) (u) (v) (w) <surface> [BOUND r]",
    ),
    ("LET", "LET name = expression"),
    ("FRAMES", "FRAMES n [FPS f]"),
];

/// Every surface-property keyword with its usage.
pub(crate) const PROPERTIES: &[(&str, &str)] = &[
    ("SPECULAR", "SPECULAR ks exponent"),
    ("REFLECT", "REFLECT kr"),
    ("TRANSMIT", "TRANSMIT kt"),
    ("IOR", "IOR n"),
    ("ATTENUATION", "ATTENUATION (r, g, b)"),
    ("CHECKER", "CHECKER (r, g, b) size"),
    ("INSIDE", "INSIDE (r, g, b)"),
];

/// What `<surface>` stands for in the usage lines.
pub(super) const SURFACE_USAGE: &str =
    "<surface> is a diffuse colour (r, g, b) or the name of a MATERIAL \
     defined earlier, then optionally SPECULAR ks exponent, REFLECT kr, TRANSMIT kt, IOR n, \
     ATTENUATION (r, g, b), CHECKER (r, g, b) size, INSIDE (r, g, b)";

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
    let mut builder = Builder::default();
    let mut names = Names::new(options.time);
    let mut offset = 0;
    let mut last_token_end = 0;
    for (i, raw) in text.split('\n').enumerate() {
        let start = offset;
        offset += raw.len() + 1;
        let tokens = lex_line(text, start, start + raw.len())
            .map_err(|e| src.error(e.span, e.message, e.label, None))?;
        let Some(last) = tokens.last() else {
            continue;
        };
        last_token_end = last.span.end;
        let mut cur = Cursor {
            src,
            tokens,
            pos: 0,
            line: i + 1,
            next_line: offset.min(text.len()),
            usage: "",
            in_surface: false,
            names: &names,
            uses_time: false,
        };
        builder.statement(&mut cur, options)?;
        builder.uses_time |= cur.uses_time;
        if let Some((name, value, uses_time)) = builder.defined.take() {
            expr::define(&mut names, name, value, uses_time, i + 1);
        }
    }
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

/// A material defined by `MATERIAL`, with its line.
type Materials = HashMap<String, (Material, usize)>;

/// The scene being assembled, statement by statement.
#[derive(Default)]
struct Builder {
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
    defined: Option<(String, f64, bool)>,
    /// Some value read so far depends on the time.
    uses_time: bool,
}

impl Builder {
    fn statement(&mut self, cur: &mut Cursor, options: &LoadOptions) -> Result<()> {
        let first = cur.peek().expect("lines without tokens are skipped");
        let word = match first.kind {
            TokenKind::Word => cur.text(&first),
            _ => return Err(cur.unexpected("a keyword at the start of the statement")),
        };
        let upper = word.to_ascii_uppercase();
        let Some(&(keyword, usage)) = STATEMENTS.iter().find(|(k, _)| *k == upper) else {
            return Err(unknown_keyword(cur, &first, word));
        };
        cur.usage = usage;
        cur.pos = 1;
        let kw = first.span.clone();
        match keyword {
            "SIZE" => {
                let (w, _) = cur.whole("the image width", 1, Scene::MAX_SIDE)?;
                let (h, _) = cur.whole("the image height", 1, Scene::MAX_SIDE)?;
                cur.end()?;
                once(cur, &kw, "SIZE", &self.size)?;
                self.size = Some(((w, h), cur.line));
            }
            "CAMERA" => {
                let eye = cur.point("the eye position")?;
                let look = cur.point("the look-at point")?;
                let up = cur.direction("the up vector")?;
                let (fov, fov_span) = cur.number("the field of view in degrees")?;
                cur.end()?;
                let camera = Camera::new(eye.v, look.v, up.v, fov).map_err(|e| {
                    let (span, label) = match e {
                        CameraError::NotFinite => (cur.statement_span(), "not finite"),
                        CameraError::NoViewDirection => (
                            Cursor::join(&eye.span, &look.span),
                            "eye and look-at are the same point",
                        ),
                        CameraError::BadUp => (up.span.clone(), "parallel to the view direction"),
                        CameraError::BadFov(_) => (fov_span.clone(), "must be in (0, 180)"),
                    };
                    cur.fail(span, format!("degenerate camera: {e}"), label)
                })?;
                once(cur, &kw, "CAMERA", &self.camera)?;
                self.camera = Some((camera, cur.line));
            }
            "BACKGROUND" | "AMBIENT" => {
                let c = cur.colour(if keyword == "AMBIENT" {
                    "the ambient light"
                } else {
                    "the background colour"
                })?;
                cur.end()?;
                let slot = if keyword == "AMBIENT" {
                    &mut self.ambient
                } else {
                    &mut self.background
                };
                once(cur, &kw, keyword, slot)?;
                *slot = Some((c.v, cur.line));
            }
            "LIGHT" => {
                let position = cur.point("the light's position")?;
                let colour = cur.colour("the light's colour")?;
                let radius = if cur.peek().is_some() {
                    cur.in_range("the light's radius", 0.0, f64::MAX)?.0
                } else {
                    0.0
                };
                let samples = if cur
                    .peek_word()
                    .is_some_and(|w| w.eq_ignore_ascii_case("SAMPLES"))
                {
                    cur.pos += 1;
                    cur.whole("the light's shadow samples", 1, Light::MAX_SAMPLES)?
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
            }
            "MATERIAL" => self.material(cur)?,
            "LET" => {
                let (name, value, uses_time, _) = expr::let_statement(cur)?;
                self.defined = Some((name, value, uses_time));
            }
            "FRAMES" => self.frames(cur, &kw)?,
            _ => self.object(cur, keyword, &kw, options)?,
        }
        Ok(())
    }

    /// `FRAMES n [FPS f]`: plain numbers, the same at every frame.
    fn frames(&mut self, cur: &mut Cursor, kw: &Span) -> Result<()> {
        let (n, _) = cur.whole("the number of frames", 1, Animation::MAX_FRAMES)?;
        let fps = if cur
            .peek_word()
            .is_some_and(|w| w.eq_ignore_ascii_case("FPS"))
        {
            cur.pos += 1;
            cur.in_range("the frame rate in frames per second", 0.01, 1000.0)?
                .0
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
        once(cur, kw, "FRAMES", &self.frames)?;
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
        let upper = name.to_ascii_uppercase();
        if upper == "BOUND" || PROPERTIES.iter().any(|p| p.0 == upper) {
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
        cur.end_after_surface()?;
        self.materials.insert(name.to_string(), (m, cur.line));
        Ok(())
    }

    fn object(
        &mut self,
        cur: &mut Cursor,
        keyword: &'static str,
        kw: &Span,
        options: &LoadOptions,
    ) -> Result<()> {
        let shape_error = |cur: &Cursor, span: Span, e: ShapeError| {
            cur.fail(
                span,
                format!("invalid {}: {e}", keyword.to_ascii_lowercase()),
                "invalid shape",
            )
        };
        let (shape, material): (Box<dyn Shape>, Material) = match keyword {
            "SPHERE" => {
                let c = cur.point("the sphere's centre")?;
                let (r, _) = cur.positive("the sphere's radius")?;
                let m = surface(cur, &self.materials)?;
                cur.end_after_surface()?;
                let s = Sphere::new(c.v, r).map_err(|e| shape_error(cur, kw.clone(), e))?;
                (Box::new(s), m)
            }
            "PLANE" => {
                let p = cur.point("a point on the plane")?;
                let n = cur.direction("the plane's normal")?;
                let m = surface(cur, &self.materials)?;
                cur.end_after_surface()?;
                let s = Plane::new(p.v, n.v).map_err(|e| shape_error(cur, n.span.clone(), e))?;
                (Box::new(s), m)
            }
            "POLYGON" => {
                let (count, count_span) = cur.number("the number of vertices")?;
                if !(count.fract() == 0.0 && count >= 3.0) {
                    return Err(cur.fail(
                        count_span,
                        format!(
                            "a polygon needs a whole number of at least 3 vertices, not {count}"
                        ),
                        "must be a whole number ≥ 3",
                    ));
                }
                let n = count.min(u32::MAX as f64) as u32;
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
                cur.end_after_surface()?;
                let s = Polygon::new(verts.iter().map(|a| a.v).collect()).map_err(|e| {
                    // Point at the vertex the message names, else at all of them.
                    let span = match vertex_named_in(&e.0, verts.len()) {
                        Some(k) => verts[k - 1].span.clone(),
                        None => Cursor::join(&verts[0].span, &verts[verts.len() - 1].span),
                    };
                    shape_error(cur, span, e)
                })?;
                (Box::new(s), m)
            }
            "BOX" | "ELLIPSOID" | "HEART" => {
                let (origin, names) = match keyword {
                    "BOX" => ("the box's corner", ["edge1", "edge2", "edge3"]),
                    "ELLIPSOID" => ("the ellipsoid's centre", ["u", "v", "w"]),
                    _ => ("the heart's position", ["u", "v", "w"]),
                };
                let p = cur.point(origin)?;
                let (u, v, w) = basis(cur, names)?;
                let m = surface(cur, &self.materials)?;
                cur.end_after_surface()?;
                check_frame(cur, &p, [&u, &v, &w], names)?;
                let span = Cursor::join(&u.span, &w.span);
                let s: Box<dyn Shape> = match keyword {
                    "BOX" => Box::new(
                        Parallelepiped::new(p.v, u.v, v.v, w.v)
                            .map_err(|e| shape_error(cur, span, e))?,
                    ),
                    "ELLIPSOID" => Box::new(
                        Ellipsoid::new(p.v, u.v, v.v, w.v)
                            .map_err(|e| shape_error(cur, span, e))?,
                    ),
                    _ => Box::new(
                        Heart::new(p.v, u.v, v.v, w.v)
                            .map_err(|e| shape_error(cur, span, e))?
                            .with_solver(options.solver),
                    ),
                };
                (s, m)
            }
            "IMPLICIT" => self.implicit(cur, options)?,
            _ => unreachable!("every statement keyword is handled"),
        };
        self.objects
            .push(Object::new(shape, material, keyword, cur.line));
        Ok(())
    }

    fn implicit(
        &mut self,
        cur: &mut Cursor,
        options: &LoadOptions,
    ) -> Result<(Box<dyn Shape>, Material)> {
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
            bound = Some(cur.positive("the bounding radius")?.0);
            cur.end()?;
        } else {
            cur.end_after_surface()?;
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
        Ok((Box::new(shape.with_solver(options.solver)), m))
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
            objects: self.objects,
        };
        Ok((scene, animation))
    }
}

/// Fails when a once-only statement was already given.
fn once<T>(cur: &Cursor, kw: &Span, keyword: &str, slot: &Option<(T, usize)>) -> Result<()> {
    match slot {
        None => Ok(()),
        Some((_, line)) => Err(cur.fail_help(
            kw.clone(),
            format!("{keyword} is given twice (first on line {line})"),
            "repeated statement",
            format!("a scene has at most one {keyword}; remove one of them"),
        )),
    }
}

/// The three non-zero basis vectors of a placed shape.
fn basis(cur: &mut Cursor, names: [&str; 3]) -> Result<(VecArg, VecArg, VecArg)> {
    let u = cur.direction(&format!("the basis vector {}", names[0]))?;
    let v = cur.direction(&format!("the basis vector {}", names[1]))?;
    let w = cur.direction(&format!("the basis vector {}", names[2]))?;
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

/// `<surface>`: a colour or a material name, then optional properties.
fn surface(cur: &mut Cursor, materials: &Materials) -> Result<Material> {
    cur.in_surface = true;
    let m = surface_inner(cur, materials);
    cur.in_surface = false;
    m
}

fn surface_inner(cur: &mut Cursor, materials: &Materials) -> Result<Material> {
    const EXPECTED: &str = "a diffuse colour (r, g, b) or a material name";
    let Some(t) = cur.peek() else {
        if cur.usage.starts_with("POLYGON") {
            return Err(cur.fail(
                cur.here(),
                format!(
                    "expected {EXPECTED}, found end of line: are there fewer vertices than the \
                     polygon's vertex count n (so that the colour was read as the last vertex)?"
                ),
                format!("expected {EXPECTED}"),
            ));
        }
        return Err(cur.unexpected(EXPECTED));
    };
    let mut m = match t.kind {
        TokenKind::Open => Material::diffuse(cur.colour("the diffuse colour")?.v),
        TokenKind::Word => {
            let word = cur.text(&t);
            if parse_number(word) != Err(NumberError::NotANumber) {
                return Err(cur.unexpected(EXPECTED));
            }
            let upper = word.to_ascii_uppercase();
            if upper == "BOUND" || PROPERTIES.iter().any(|p| p.0 == upper) {
                return Err(cur.fail(
                    t.span,
                    format!("expected {EXPECTED} before {upper}, found {upper}"),
                    "surface properties follow the colour",
                ));
            }
            match materials.get(word) {
                Some((m, _)) => {
                    cur.pos += 1;
                    m.clone()
                }
                None => return Err(unknown_material(cur, &t, word, materials)),
            }
        }
        _ => return Err(cur.unexpected(EXPECTED)),
    };
    let mut seen: Vec<&str> = Vec::new();
    while let Some(word) = cur.peek_word() {
        let upper = word.to_ascii_uppercase();
        let Some(&(prop, _)) = PROPERTIES.iter().find(|p| p.0 == upper) else {
            break;
        };
        let span = cur.here();
        if seen.contains(&prop) {
            return Err(cur.fail(
                span,
                format!("{prop} is given twice for this surface"),
                "repeated property",
            ));
        }
        seen.push(prop);
        cur.pos += 1;
        match prop {
            "SPECULAR" => {
                m.specular = cur.in_range("the specular weight ks", 0.0, f64::MAX)?.0;
                m.shininess = cur.in_range("the specular exponent", 1.0, f64::MAX)?.0;
            }
            "REFLECT" => m.reflect = cur.in_range("the reflection weight kr", 0.0, 1.0)?.0,
            "TRANSMIT" => m.transmit = cur.in_range("the transmission weight kt", 0.0, 1.0)?.0,
            "IOR" => m.ior = cur.positive("the index of refraction")?.0,
            "ATTENUATION" => m.attenuation = cur.colour("the attenuation")?.v,
            "CHECKER" => {
                let c = cur.colour("the checker's second colour")?;
                let (size, _) = cur.positive("the checker's cell size")?;
                m.checker = Some((c.v, size));
            }
            "INSIDE" => m.inside = Some(cur.colour("the inside colour")?.v),
            _ => unreachable!("every property is handled"),
        }
    }
    Ok(m)
}

/// The error for a surface naming a material that is not (yet) defined.
fn unknown_material(cur: &Cursor, t: &Token, word: &str, materials: &Materials) -> SceneError {
    let message = format!("unknown material `{}`", shorten(word, 30));
    let help = if let Some(line) = defined_later(cur, word) {
        format!(
            "`{word}` is defined on line {line}, after this use: a MATERIAL must come before the \
             objects that use it"
        )
    } else if let Some(name) = materials.keys().find(|k| k.eq_ignore_ascii_case(word)) {
        format!("did you mean `{name}`? (material names are case-sensitive)")
    } else if materials.is_empty() {
        "no MATERIAL is defined before this line; write a colour (r, g, b) or define one with \
         `MATERIAL name <surface>`"
            .into()
    } else {
        let mut names: Vec<&str> = materials.keys().map(String::as_str).collect();
        names.sort_unstable();
        match suggest(word, names.iter().copied()) {
            Some(s) => format!("did you mean `{s}`?"),
            None => format!("materials defined so far: {}", names.join(", ")),
        }
    };
    cur.fail_help(
        t.span.clone(),
        message,
        "not defined before this line",
        help,
    )
}

/// The line of a later `MATERIAL name …` statement, if any.
fn defined_later(cur: &Cursor, name: &str) -> Option<usize> {
    let text = cur.src.text;
    let mut offset = cur.next_line;
    let mut line = cur.line + 1;
    while offset < text.len() {
        let end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
        if let Ok(toks) = lex_line(text, offset, end) {
            if toks.len() >= 2
                && text[toks[0].span.clone()].eq_ignore_ascii_case("MATERIAL")
                && &text[toks[1].span.clone()] == name
            {
                return Some(line);
            }
        }
        offset = end + 1;
        line += 1;
    }
    None
}

/// The error for a statement starting with an unknown word.
fn unknown_keyword(cur: &Cursor, t: &Token, word: &str) -> SceneError {
    let upper = word.to_ascii_uppercase();
    let span = t.span.clone();
    if let Some(&(p, _)) = PROPERTIES.iter().find(|p| p.0 == upper) {
        return cur.fail_help(
            span,
            format!("{p} is a surface property, not a statement"),
            "not a statement",
            "surface properties follow an object's colour on the same line, e.g. \
             `SPHERE (0, 0, 0) 1 (0.8, 0.1, 0.1) SPECULAR 0.5 40`",
        );
    }
    let names = STATEMENTS.iter().map(|s| s.0);
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
