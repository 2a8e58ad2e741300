//! surf's `.pic` scripts (statements ending in `;`, `//` and `/* */` comments) as kardia scene
//! text.
//!
//! surf draws the surface scaled by `1/scale_x` … (so a surface point `p` is at `p/scale` on
//! the screen), turned by its `rotate` statements in order, clipped to the ball of `radius`
//! about the origin, and seen along −z by a parallel projection of the window −10…10; lights
//! sit in the screen's coordinates, whose y runs downwards. kardia writes the same: the
//! surface as an `IMPLICIT` equation whose basis is the rotation's columns over the scales
//! with y turned upwards, `BOUND radius·scale`, an orthographic camera 20 units tall. (The
//! conventions — `rotate` by −angle about a right-handed axis, y down — are those whose
//! pictures match the ones surf draws of its gallery.) `double` names become `LET` names, `poly` names are
//! written out in the equation. docs/surfer.md lists every statement.

use std::collections::BTreeMap;

use super::{linear, mat_mul, num, vector, SceneText, Translation, Warning};
use crate::scene::SceneError;
use crate::shapes::implicit::equation;

/// The height (and width) of surf's window in screen units.
pub const WINDOW: f64 = 20.0;

/// How far along +z the orthographic camera's plane is put (outside any clip ball surf draws).
const EYE_DISTANCE: f64 = 1000.0;

/// One statement: its text (comments removed, trimmed) and the line it starts on.
#[derive(Debug, Clone, PartialEq)]
struct Statement {
    text: String,
    line: usize,
}

/// Splits a script into statements at `;`, dropping comments. Text after the last `;` is a
/// statement too (surf would complain; kardia reads it).
fn statements(text: &str) -> Vec<Statement> {
    let mut out = Vec::new();
    let mut current = String::new();
    let mut start_line = 1;
    let mut line = 1;
    let mut chars = text.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if c == '\n' {
            line += 1;
        }
        if in_string {
            current.push(c);
            if c == '"' {
                in_string = false;
            }
            continue;
        }
        match c {
            '"' => {
                in_string = true;
                current.push(c);
            }
            '/' if chars.peek() == Some(&'/') => {
                for n in chars.by_ref() {
                    if n == '\n' {
                        line += 1;
                        current.push(' ');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                let mut last = ' ';
                for n in chars.by_ref() {
                    if n == '\n' {
                        line += 1;
                    }
                    if last == '*' && n == '/' {
                        break;
                    }
                    last = n;
                }
                current.push(' ');
            }
            ';' => {
                let t = current.trim();
                if !t.is_empty() {
                    out.push(Statement {
                        text: t.to_string(),
                        line: start_line,
                    });
                }
                current.clear();
            }
            c => {
                if current.trim().is_empty() && !c.is_whitespace() {
                    start_line = line;
                }
                current.push(c);
            }
        }
    }
    let t = current.trim();
    if !t.is_empty() {
        out.push(Statement {
            text: t.to_string(),
            line: start_line,
        });
    }
    out
}

/// Statements surf knows and kardia ignores (a warning names each one used).
const IGNORED: &[&str] = &[
    "illumination",
    "transmitted",
    "transparence",
    "thickness",
    "antialiasing",
    "root_finder",
    "epsilon",
    "clip",
    "filename",
    "color_file_format",
    "save_color_image",
    "clear_screen",
    "perspective",
    "spec_z",
    "iterations",
];

/// The script as read: numbers by name, polynomials by name, the surface and its rotation.
struct Script<'a> {
    text: &'a str,
    file: &'a str,
    /// `double`/`int` names and every numeric setting, with their values.
    numbers: BTreeMap<String, f64>,
    /// `poly` names with their equations (names inside already written out).
    polys: BTreeMap<String, String>,
    /// The `double`/`int` names in the order defined, with their lines (for `LET`).
    lets: Vec<(String, usize)>,
    /// The lines on which each setting was last given.
    lines: BTreeMap<String, usize>,
    surface: Option<(String, usize)>,
    rotation: [[f64; 3]; 3],
    warnings: Vec<Warning>,
}

/// A name as surf writes it: letters, digits and `_`, not starting with a digit.
fn is_name(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The rotation by `angle` radians about axis 0, 1 or 2 (right-handed), by rows.
fn rotation(axis: usize, angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = angle.sin_cos();
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut m = [[0.0; 3]; 3];
    m[axis][axis] = 1.0;
    m[i][i] = c;
    m[j][j] = c;
    m[i][j] = -s;
    m[j][i] = s;
    m
}

impl Script<'_> {
    fn error(&self, line: usize, message: impl Into<String>) -> SceneError {
        super::at_line(self.text, self.file, line, message, "here")
    }

    fn warn(&mut self, line: usize, message: String) {
        self.warnings.push(Warning { line, message });
    }

    /// The value of a constant expression (numbers, `double` names, pi, sqrt …).
    fn value(&self, expr: &str, line: usize) -> Result<f64, SceneError> {
        let lookup = |name: &str| self.numbers.get(name).copied();
        let tree = equation::parse_with(expr, &lookup)
            .map_err(|e| self.error(line, format!("in '{expr}': {}", e.message)))?;
        let (v0, v1) = (tree.eval([0.0; 3]), tree.eval([1.0, 2.0, 3.0]));
        if v0.to_bits() != v1.to_bits() && !(v0.is_nan() && v1.is_nan()) {
            return Err(self.error(line, format!("'{expr}' must be a number, not a polynomial")));
        }
        if !v0.is_finite() {
            return Err(self.error(line, format!("'{expr}' is not a finite number")));
        }
        Ok(v0)
    }

    /// `expr` with every `poly` name written out in parentheses.
    fn written_out(&self, expr: &str) -> String {
        let mut out = String::new();
        let mut word = String::new();
        let flush = |word: &mut String, out: &mut String| {
            if let Some(p) = self.polys.get(word.as_str()) {
                out.push('(');
                out.push_str(p);
                out.push(')');
            } else {
                out.push_str(word);
            }
            word.clear();
        };
        for c in expr.chars() {
            if c.is_ascii_alphanumeric() || c == '_' || (c == '.' && word.is_empty()) {
                word.push(c);
            } else {
                flush(&mut word, &mut out);
                out.push(c);
            }
        }
        flush(&mut word, &mut out);
        out
    }

    fn statement(&mut self, s: &Statement) -> Result<(), SceneError> {
        let text = s.text.as_str();
        let line = s.line;
        let Some((lhs, rhs)) = text.split_once('=') else {
            let command = text.trim();
            if command == "draw_surface" {
                return Ok(());
            }
            if IGNORED.contains(&command) {
                self.warn(line, format!("'{command}' ignored"));
                return Ok(());
            }
            if is_name(command) {
                self.warn(line, format!("unknown command '{command}' ignored"));
                return Ok(());
            }
            return Err(self.error(
                line,
                format!("expected 'name = value;' or a command such as draw_surface, not '{text}'"),
            ));
        };
        let rhs = rhs.trim();
        let words: Vec<&str> = lhs.split_whitespace().collect();
        let (kind, name) = match words.as_slice() {
            [name] => (None, *name),
            [kind, name] => (Some(*kind), *name),
            _ => {
                return Err(self.error(
                    line,
                    format!("expected one name before '=', not '{}'", lhs.trim()),
                ))
            }
        };
        if !is_name(name) {
            return Err(self.error(line, format!("'{name}' is not a name")));
        }
        match kind {
            Some("poly") => {
                let written = self.written_out(rhs);
                self.polys.insert(name.to_string(), written);
                Ok(())
            }
            Some("double") | Some("int") => {
                if name.eq_ignore_ascii_case("pi") {
                    // surf has no π (scripts write `double PI = 2*arcsin(1);`); kardia has it.
                    return Ok(());
                }
                let v = self.value(rhs, line)?;
                if !self.numbers.contains_key(name) {
                    self.lets.push((name.to_string(), line));
                }
                self.numbers.insert(name.to_string(), v);
                self.lines.insert(name.to_string(), line);
                Ok(())
            }
            Some(other) => Err(self.error(
                line,
                format!("unknown type '{other}': kardia reads double, int and poly"),
            )),
            None if name == "surface" => self.surface(rhs, line),
            None if name.starts_with("surface") && name[7..].parse::<u32>().is_ok() => {
                self.warn(line, format!("'{name}' ignored: kardia draws one surface"));
                Ok(())
            }
            None if IGNORED.contains(&name) => {
                self.warn(line, format!("'{name}' ignored"));
                Ok(())
            }
            None if self.polys.contains_key(name) => {
                let written = self.written_out(rhs);
                self.polys.insert(name.to_string(), written);
                Ok(())
            }
            None => {
                if !is_setting(name) && !self.numbers.contains_key(name) {
                    self.warn(line, format!("unknown setting '{name}' ignored"));
                    return Ok(());
                }
                let v = self.value(rhs, line)?;
                self.numbers.insert(name.to_string(), v);
                self.lines.insert(name.to_string(), line);
                Ok(())
            }
        }
    }

    /// `surface = expr;` or `surface = rotate(surface, angle, xAxis);`.
    fn surface(&mut self, rhs: &str, line: usize) -> Result<(), SceneError> {
        let Some(args) = rhs
            .strip_prefix("rotate")
            .map(str::trim_start)
            .and_then(|r| r.strip_prefix('('))
            .and_then(|r| r.trim_end().strip_suffix(')'))
        else {
            self.surface = Some((self.written_out(rhs), line));
            self.rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            return Ok(());
        };
        let parts: Vec<&str> = args.split(',').map(str::trim).collect();
        let [what, angle, axis] = parts.as_slice() else {
            return Err(self.error(line, "rotate takes (surface, angle, xAxis|yAxis|zAxis)"));
        };
        if *what != "surface" || self.surface.is_none() {
            return Err(self.error(
                line,
                "kardia rotates only the surface: write surface = rotate(surface, angle, xAxis) after surface = …",
            ));
        }
        let axis = match *axis {
            "xAxis" => 0,
            "yAxis" => 1,
            "zAxis" => 2,
            other => {
                return Err(self.error(
                    line,
                    format!("unknown axis '{other}': write xAxis, yAxis or zAxis"),
                ))
            }
        };
        let angle = self.value(angle, line)?;
        self.rotation = mat_mul(&rotation(axis, -angle), &self.rotation);
        Ok(())
    }

    fn number(&self, name: &str, default: f64) -> f64 {
        self.numbers.get(name).copied().unwrap_or(default)
    }

    fn line_of(&self, name: &str) -> usize {
        self.lines.get(name).copied().unwrap_or(0)
    }

    /// A colour of 0…255 components `{prefix}red` … as linear 0…1.
    fn colour(&self, prefix: &str, default: [f64; 3]) -> [f64; 3] {
        let c = ["red", "green", "blue"]
            .iter()
            .zip(default)
            .map(|(part, d)| self.number(&format!("{prefix}{part}"), d) / 255.0);
        let c: Vec<f64> = c.collect();
        linear([c[0], c[1], c[2]])
    }
}

/// The most lights a script has (`light1_…` … `light9_…`).
pub const LIGHTS: usize = 9;

/// Whether `name` is a numeric setting kardia reads.
fn is_setting(name: &str) -> bool {
    const PLAIN: &[&str] = &[
        "width",
        "height",
        "radius",
        "scale_x",
        "scale_y",
        "scale_z",
        "rot_x",
        "rot_y",
        "rot_z",
        "ambient",
        "diffuse",
        "reflected",
        "smoothness",
    ];
    if PLAIN.contains(&name) {
        return true;
    }
    for prefix in ["background_", "surface_", "inside_"] {
        if let Some(part) = name.strip_prefix(prefix) {
            return matches!(part, "red" | "green" | "blue");
        }
    }
    name.strip_prefix("light")
        .and_then(|rest| rest.split_once('_'))
        .is_some_and(|(n, part)| {
            n.parse::<usize>().is_ok_and(|n| (1..=LIGHTS).contains(&n))
                && matches!(part, "x" | "y" | "z" | "vol" | "red" | "green" | "blue")
        })
}

/// Translates a `.pic` script into kardia scene text (see the module documentation); `file`
/// names it in errors. A script that sets no `surface`, or a malformed statement, is an error
/// at its line; statements kardia ignores are warnings naming them.
pub fn translate(text: &str, file: &str) -> Result<Translation, SceneError> {
    let mut script = Script {
        text,
        file,
        numbers: BTreeMap::new(),
        polys: BTreeMap::new(),
        lets: Vec::new(),
        lines: BTreeMap::new(),
        surface: None,
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        warnings: Vec::new(),
    };
    for s in statements(text) {
        script.statement(&s)?;
    }
    let Some((surface, surface_line)) = script.surface.clone() else {
        return Err(super::at_line(
            text,
            file,
            1,
            "a .pic script needs a surface: write surface = …;",
            "no surface in this script",
        ));
    };
    if surface.contains('"') {
        return Err(script.error(surface_line, "the surface may not contain '\"'"));
    }
    let s = &script;
    let mut out = SceneText::default();
    out.push(
        format!("# {file}: translated by kardia from surf's .pic"),
        0,
    );
    let width = s.number("width", 512.0).round().clamp(1.0, 32768.0);
    let height = s.number("height", 512.0).round().clamp(1.0, 32768.0);
    out.push(
        format!("SIZE {} {}", num(width), num(height)),
        s.line_of("width").max(s.line_of("height")),
    );
    // The window −10…10 spans the picture's shorter side.
    let view_height = if height <= width {
        WINDOW
    } else {
        WINDOW * height / width
    };
    out.push(
        format!(
            "CAMERA (0, 0, {EYE_DISTANCE}) (0, 0, 0) (0, 1, 0) ORTHOGRAPHIC {}",
            num(view_height)
        ),
        0,
    );
    out.push(
        format!(
            "BACKGROUND {}",
            vector(s.colour("background_", [0.0, 0.0, 0.0]))
        ),
        s.line_of("background_red"),
    );
    let ambient = s.number("ambient", 35.0) / 100.0;
    let diffuse = s.number("diffuse", 60.0) / 100.0;
    out.push(
        format!("AMBIENT {}", vector([ambient; 3])),
        s.line_of("ambient"),
    );
    for i in 1..=LIGHTS {
        let key = |part: &str| format!("light{i}_{part}");
        let given = ["x", "y", "z", "vol", "red", "green", "blue"]
            .iter()
            .any(|p| s.numbers.contains_key(&key(p)));
        let (default_vol, default_colour) = if i == 1 { (50.0, 255.0) } else { (0.0, 255.0) };
        if !given && i != 1 {
            continue;
        }
        let vol = s.number(&key("vol"), default_vol) / 100.0;
        let colour = s.colour(&format!("light{i}_"), [default_colour; 3]);
        let light = colour.map(|c| c * vol * diffuse);
        if light.iter().all(|&c| c <= 0.0) {
            continue;
        }
        // Screen y runs down; kardia's up.
        let position = [
            s.number(&key("x"), -100.0),
            -s.number(&key("y"), 100.0),
            s.number(&key("z"), 100.0),
        ];
        out.push(
            format!("LIGHT {} {}", vector(position), vector(light)),
            s.line_of(&key("vol")).max(s.line_of(&key("x"))),
        );
    }
    for (name, line) in &s.lets {
        out.push(format!("LET {name} = {}", num(s.numbers[name])), *line);
    }
    let scale = [
        s.number("scale_x", 1.0),
        s.number("scale_y", 1.0),
        s.number("scale_z", 1.0),
    ];
    if scale.iter().any(|&k| !(k > 0.0 && k.is_finite())) {
        return Err(s.error(
            s.line_of("scale_x").max(1),
            format!("the scales must be greater than 0, not {scale:?}"),
        ));
    }
    let mut rotation = s.rotation;
    for (axis, name) in ["rot_x", "rot_y", "rot_z"].iter().enumerate() {
        let angle = s.number(name, 0.0);
        if angle != 0.0 {
            rotation = mat_mul(&self::rotation(axis, -angle), &rotation);
        }
    }
    // Screen = rotation · surface / scale: the images of x, y and z are the columns over the
    // scales, with the screen's y (down) turned up.
    let basis: [[f64; 3]; 3] = std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            let c = rotation[i][j] / scale[j];
            if i == 1 {
                -c
            } else {
                c
            }
        })
    });
    let radius = s.number("radius", 10.0);
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(s.error(
            s.line_of("radius").max(1),
            format!("radius must be greater than 0, not {radius}"),
        ));
    }
    let mut warnings = script.warnings.clone();
    let smallest = scale.iter().copied().fold(f64::INFINITY, f64::min);
    if scale.iter().any(|&k| k != smallest) {
        warnings.push(Warning {
            line: s
                .line_of("scale_x")
                .max(s.line_of("scale_y"))
                .max(s.line_of("scale_z")),
            message: "unequal scale_x, scale_y, scale_z: kardia clips to the ball of the smallest"
                .into(),
        });
    }
    let front = s.colour("surface_", [255.0, 204.0, 0.0]);
    let back = s.colour("inside_", [255.0 * 0.8, 204.0 * 0.8, 0.0]);
    let reflected = s.number("reflected", 60.0) / 100.0;
    let smoothness = s.number("smoothness", 13.0).max(1.0);
    let mut surface_props = vector(front);
    if reflected > 0.0 {
        surface_props += &format!(" SPECULAR {} {}", num(reflected), num(smoothness));
    }
    surface_props += &format!(" INSIDE {}", vector(back));
    out.push(
        format!(
            "IMPLICIT \"{}\" (0, 0, 0) {} {} {} {} BOUND {}",
            surface.split_whitespace().collect::<Vec<_>>().join(" "),
            vector(basis[0]),
            vector(basis[1]),
            vector(basis[2]),
            surface_props,
            num(radius * smallest)
        ),
        surface_line,
    );
    Ok(out.finish(warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statements_split_at_semicolons_without_comments() {
        let got = statements("a = 1; b=2;// c = 3;\n/* d = 4;\n */ e = 5\n;\nf");
        let want: Vec<(String, usize)> = vec![
            ("a = 1".into(), 1),
            ("b=2".into(), 1),
            ("e = 5".into(), 3),
            ("f".into(), 5),
        ];
        let got: Vec<(String, usize)> = got.into_iter().map(|s| (s.text, s.line)).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn rotations_are_right_handed() {
        let quarter = std::f64::consts::FRAC_PI_2;
        let about_z = rotation(2, quarter);
        let x = super::super::mat_vec(&about_z, [1.0, 0.0, 0.0]);
        assert!((x[1] - 1.0).abs() < 1e-15 && x[0].abs() < 1e-15);
        let about_x = rotation(0, quarter);
        let y = super::super::mat_vec(&about_x, [0.0, 1.0, 0.0]);
        assert!((y[2] - 1.0).abs() < 1e-15);
        let about_y = rotation(1, quarter);
        let z = super::super::mat_vec(&about_y, [0.0, 0.0, 1.0]);
        assert!((z[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn settings_are_recognised_by_name() {
        for name in ["width", "light9_vol", "light1_x", "inside_blue", "rot_z"] {
            assert!(is_setting(name), "{name}");
        }
        for name in ["light0_x", "light10_x", "light1_w", "surface_alpha", "zoom"] {
            assert!(!is_setting(name), "{name}");
        }
    }
}
