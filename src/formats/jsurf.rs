//! SURFER's `.jsurf` files (Java properties, one `key=value` a line) as kardia scene text.
//!
//! SURFER shows the unit ball of its view: the surface, scaled by `10^-scale_factor` and turned
//! by `rotation_matrix`, is clipped to that ball and seen by an orthographic camera
//! `camera_height` tall (or a perspective one of vertical field `camera_fov_y`) placed by
//! `camera_transform`, lit by up to eight lights given in the camera's coordinates. kardia
//! writes the same: the surface as an `IMPLICIT` equation whose basis is the rotation's rows
//! over `10^scale_factor` with `BOUND 10^scale_factor`, its parameters `a`…`d` as `LET` names.
//! docs/surfer.md lists every key.

use std::collections::BTreeMap;

use super::{linear, mat_vec, num, transpose, vector, SceneText, Translation, Warning};
use crate::scene::SceneError;

/// The image size the translation asks for (SURFER draws square pictures).
pub const SIZE: u32 = 512;

/// How far behind the ball's centre an orthographic camera's plane is put (the view's unit
/// ball must lie in front of it).
const ORTHOGRAPHIC_DISTANCE: f64 = 3.0;

/// `n` numbers in words: "a number", "3 numbers".
fn count(n: usize) -> String {
    if n == 1 {
        "a number".into()
    } else {
        format!("{n} numbers")
    }
}

/// One property: its value and the line it is on.
#[derive(Debug, Clone)]
struct Property {
    value: String,
    line: usize,
}

/// Reads the properties (later keys replace earlier ones), with their lines.
fn properties(text: &str) -> BTreeMap<String, Property> {
    let mut out = BTreeMap::new();
    let mut lines = text.lines().enumerate().peekable();
    while let Some((i, raw)) = lines.next() {
        let mut line = raw.trim_start().to_string();
        if line.is_empty() || line.starts_with('#') || line.starts_with('!') {
            continue;
        }
        // A line ending in an odd number of backslashes continues on the next.
        while line.ends_with('\\') && (line.len() - line.trim_end_matches('\\').len()) % 2 == 1 {
            line.pop();
            match lines.next() {
                Some((_, next)) => line.push_str(next.trim_start()),
                None => break,
            }
        }
        let (key, value) = split_property(&line);
        out.insert(
            key,
            Property {
                value: value.trim().to_string(),
                line: i + 1,
            },
        );
    }
    out
}

/// A property line's key and value: split at the first unescaped `=`, `:` or white space.
fn split_property(line: &str) -> (String, String) {
    let mut key = String::new();
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' => {
                if let Some(n) = chars.next() {
                    key.push(n);
                }
            }
            '=' | ':' => break,
            c if c.is_whitespace() => {
                // `key = value` or `key value`.
                while chars.peek().is_some_and(|c| c.is_whitespace()) {
                    chars.next();
                }
                if chars.peek().is_some_and(|&c| c == '=' || c == ':') {
                    chars.next();
                }
                break;
            }
            c => key.push(c),
        }
    }
    let rest: String = chars.collect();
    (key, unescape(rest.trim_start()))
}

/// Java properties escapes in a value (`\\`, `\=`, `\:`, `\n`, `\t`, `\uXXXX`).
fn unescape(value: &str) -> String {
    let mut out = String::new();
    let mut chars = value.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some('u') => {
                let hex: String = chars.by_ref().take(4).collect();
                if let Some(ch) = u32::from_str_radix(&hex, 16).ok().and_then(char::from_u32) {
                    out.push(ch);
                }
            }
            Some(other) => out.push(other),
            None => {}
        }
    }
    out
}

/// The keys kardia reads, besides the numbered light keys.
pub const KEYS: &[&str] = &[
    "surface_equation",
    "surface_parameter_a",
    "surface_parameter_b",
    "surface_parameter_c",
    "surface_parameter_d",
    "scale_factor",
    "rotation_matrix",
    "camera_type",
    "camera_transform",
    "camera_fov_y",
    "camera_height",
    "background_color",
    "front_material_color",
    "back_material_color",
    "front_material_ambient_intensity",
    "front_material_diffuse_intensity",
    "front_material_specular_intensity",
    "front_material_specular_iIntensity",
    "front_material_shininess",
    "back_material_ambient_intensity",
    "back_material_diffuse_intensity",
    "back_material_specular_intensity",
    "back_material_specular_iIntensity",
    "back_material_shininess",
];

/// The most lights a file has (`light_*_0` … `light_*_7`).
pub const LIGHTS: usize = 8;

/// Whether `key` is a light key kardia reads (`light_position_3`, …).
fn is_light_key(key: &str) -> bool {
    ["position", "color", "intensity", "status"]
        .iter()
        .any(|part| {
            key.strip_prefix("light_")
                .and_then(|k| k.strip_prefix(part))
                .and_then(|k| k.strip_prefix('_'))
                .and_then(|n| n.parse::<usize>().ok())
                .is_some_and(|n| n < LIGHTS)
        })
}

/// The file's properties with their typed readers (errors at the value's line).
struct Reader<'a> {
    props: BTreeMap<String, Property>,
    text: &'a str,
    file: &'a str,
}

impl Reader<'_> {
    fn line(&self, key: &str) -> usize {
        self.props.get(key).map_or(0, |p| p.line)
    }

    fn error(&self, key: &str, message: String) -> SceneError {
        super::at_line(self.text, self.file, self.line(key).max(1), message, "here")
    }

    /// `n` numbers of `key`, or `default` when the key is absent.
    fn numbers<const N: usize>(
        &self,
        key: &str,
        default: [f64; N],
    ) -> Result<[f64; N], SceneError> {
        let Some(p) = self.props.get(key) else {
            return Ok(default);
        };
        let values: Vec<f64> = p
            .value
            .split_whitespace()
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                self.error(
                    key,
                    format!("{key} must be {}, not '{}'", count(N), p.value),
                )
            })?;
        // A colour may carry a fourth (alpha) component, which kardia ignores.
        if values.len() == N || (N == 3 && values.len() == 4) {
            return Ok(std::array::from_fn(|i| values[i]));
        }
        Err(self.error(
            key,
            format!(
                "{key} must be {}, not {} ('{}')",
                count(N),
                values.len(),
                p.value
            ),
        ))
    }

    fn number(&self, key: &str, default: f64) -> Result<f64, SceneError> {
        self.numbers::<1>(key, [default]).map(|[v]| v)
    }

    /// A 4×4 matrix (row by row) as its upper-left 3×3 block and its last column; `shift`
    /// is the last column's default (the rest defaults to the identity).
    fn matrix(&self, key: &str, shift: [f64; 3]) -> Result<([[f64; 3]; 3], [f64; 3]), SceneError> {
        let default = [
            1.0, 0.0, 0.0, shift[0], 0.0, 1.0, 0.0, shift[1], 0.0, 0.0, 1.0, shift[2], 0.0, 0.0,
            0.0, 1.0,
        ];
        let m = self.numbers::<16>(key, default)?;
        let rot = std::array::from_fn(|i| std::array::from_fn(|j| m[4 * i + j]));
        Ok((rot, [m[3], m[7], m[11]]))
    }
}

/// Translates a `.jsurf` file into kardia scene text (see the module documentation); `file`
/// names it in errors. A file without `surface_equation` or with a malformed value is an
/// error at its line; keys kardia does not read are warnings naming them.
pub fn translate(text: &str, file: &str) -> Result<Translation, SceneError> {
    let r = Reader {
        props: properties(text),
        text,
        file,
    };
    let mut warnings = Vec::new();
    for (key, p) in &r.props {
        if !KEYS.contains(&key.as_str()) && !is_light_key(key) {
            warnings.push(Warning {
                line: p.line,
                message: format!("unknown key '{key}' ignored"),
            });
        }
    }
    let Some(equation) = r.props.get("surface_equation") else {
        return Err(super::at_line(
            text,
            file,
            1,
            "a .jsurf file needs a surface_equation",
            "no surface_equation in this file",
        ));
    };
    if equation.value.contains('"') {
        return Err(r.error(
            "surface_equation",
            "surface_equation may not contain '\"'".into(),
        ));
    }
    let mut out = SceneText::default();
    out.push(
        format!("# {file}: translated by kardia from SURFER's .jsurf"),
        0,
    );
    out.push(format!("SIZE {SIZE} {SIZE}"), 0);

    // The camera: its transform takes world points to the camera's (looking along −z, +y up).
    // Without one, SURFER's usual: one unit back along +z.
    let (cam_rot, cam_t) = r.matrix("camera_transform", [0.0, 0.0, -1.0])?;
    let to_world = transpose(&cam_rot);
    let position = mat_vec(&to_world, cam_t).map(|c| -c);
    let forward = mat_vec(&to_world, [0.0, 0.0, -1.0]);
    let up = mat_vec(&to_world, [0.0, 1.0, 0.0]);
    let camera_type = r
        .props
        .get("camera_type")
        .map_or("ORTHOGRAPHIC_CAMERA", |p| p.value.as_str());
    let camera_line = r.line("camera_type");
    match camera_type {
        "ORTHOGRAPHIC_CAMERA" | "ORTHOGRAPHIC" => {
            let height = r.number("camera_height", 2.0)?;
            if height.is_nan() || height <= 0.0 {
                return Err(r.error(
                    "camera_height",
                    format!("camera_height must be greater than 0, not {height}"),
                ));
            }
            // The plane of the rays well outside the view's unit ball, on the camera's axis.
            let along =
                position[0] * forward[0] + position[1] * forward[1] + position[2] * forward[2];
            let shift = -along - ORTHOGRAPHIC_DISTANCE;
            let eye: [f64; 3] = std::array::from_fn(|i| position[i] + shift * forward[i]);
            let look: [f64; 3] = std::array::from_fn(|i| eye[i] + forward[i]);
            out.push(
                format!(
                    "CAMERA {} {} {} ORTHOGRAPHIC {}",
                    vector(eye),
                    vector(look),
                    vector(up),
                    num(height)
                ),
                r.line("camera_height").max(camera_line),
            );
        }
        "PERSPECTIVE_CAMERA" | "PERSPECTIVE" => {
            let fov_y = r.number("camera_fov_y", 60.0)?;
            if !(fov_y > 0.0 && fov_y < 180.0) {
                return Err(r.error(
                    "camera_fov_y",
                    format!("camera_fov_y must be greater than 0 and less than 180, not {fov_y}"),
                ));
            }
            let look: [f64; 3] = std::array::from_fn(|i| position[i] + forward[i]);
            // A square image: the horizontal field is the vertical one.
            out.push(
                format!(
                    "CAMERA {} {} {} {}",
                    vector(position),
                    vector(look),
                    vector(up),
                    num(fov_y)
                ),
                r.line("camera_fov_y").max(camera_line),
            );
        }
        other => {
            return Err(r.error(
                "camera_type",
                format!(
                    "unknown camera_type '{other}': write ORTHOGRAPHIC_CAMERA or PERSPECTIVE_CAMERA"
                ),
            ))
        }
    }

    let background = r.numbers("background_color", [1.0, 1.0, 1.0])?;
    out.push(
        format!("BACKGROUND {}", vector(linear(background))),
        r.line("background_color"),
    );
    let ambient = r.number("front_material_ambient_intensity", 0.4)?;
    let diffuse = r.number("front_material_diffuse_intensity", 0.8)?;
    out.push(
        format!("AMBIENT {}", vector([ambient; 3])),
        r.line("front_material_ambient_intensity"),
    );
    for side in ["ambient_intensity", "diffuse_intensity", "shininess"] {
        let (front_key, back_key) = (
            format!("front_material_{side}"),
            format!("back_material_{side}"),
        );
        if let (Some(f), Some(b)) = (r.props.get(&front_key), r.props.get(&back_key)) {
            if f.value != b.value {
                warnings.push(Warning {
                    line: b.line,
                    message: format!(
                        "{back_key} differs from {front_key}: kardia shades both sides with the front's"
                    ),
                });
            }
        }
    }

    for i in 0..LIGHTS {
        let status_key = format!("light_status_{i}");
        let on = match r.props.get(&status_key).map(|p| p.value.as_str()) {
            None => i == 0,
            Some("ON") => true,
            Some("OFF") => false,
            Some(other) => {
                return Err(r.error(
                    &status_key,
                    format!("{status_key} must be ON or OFF, not '{other}'"),
                ))
            }
        };
        if !on {
            continue;
        }
        let position_key = format!("light_position_{i}");
        let p = r.numbers(&position_key, [-100.0, 100.0, 100.0])?;
        let world: [f64; 3] = mat_vec(&to_world, std::array::from_fn(|k| p[k] - cam_t[k]));
        let colour = linear(r.numbers(&format!("light_color_{i}"), [1.0; 3])?);
        let intensity = r.number(&format!("light_intensity_{i}"), 1.0)?;
        let light = colour.map(|c| c * intensity * diffuse);
        out.push(
            format!("LIGHT {} {}", vector(world), vector(light)),
            r.line(&position_key).max(r.line(&status_key)),
        );
    }

    for name in ["a", "b", "c", "d"] {
        let key = format!("surface_parameter_{name}");
        if let Some(p) = r.props.get(&key) {
            let v = r.number(&key, 0.0)?;
            out.push(format!("LET {name} = {}", num(v)), p.line);
        }
    }

    let scale_exponent = r.number("scale_factor", 0.0)?;
    let radius = 10f64.powf(scale_exponent);
    if !(radius.is_finite() && radius > 0.0) {
        return Err(r.error(
            "scale_factor",
            format!("scale_factor {scale_exponent} is out of range"),
        ));
    }
    let (rotation, _) = r.matrix("rotation_matrix", [0.0; 3])?;
    // World (view) = rotation · surface / radius: the images of x, y and z are the rows.
    let basis = rotation.map(|row| row.map(|c| c / radius));
    let front = linear(r.numbers("front_material_color", [0.7, 0.5, 0.3])?);
    let back = linear(r.numbers("back_material_color", [0.8, 0.2, 0.2])?);
    let specular = match r.props.get("front_material_specular_iIntensity") {
        Some(_) => r.number("front_material_specular_iIntensity", 0.5)?,
        None => r.number("front_material_specular_intensity", 0.5)?,
    };
    let shininess = r.number("front_material_shininess", 30.0)?.max(1.0);
    let mut surface = vector(front);
    if specular > 0.0 {
        surface += &format!(" SPECULAR {} {}", num(specular), num(shininess));
    }
    surface += &format!(" INSIDE {}", vector(back));
    out.push(
        format!(
            "IMPLICIT \"{}\" (0, 0, 0) {} {} {} {} BOUND {}",
            equation.value,
            vector(basis[0]),
            vector(basis[1]),
            vector(basis[2]),
            surface,
            num(radius)
        ),
        equation.line,
    );
    Ok(out.finish(warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_take_every_separator_escape_and_continuation() {
        let props = properties(
            "# comment\n! also\nk1=v1\nk2 : v2\nk3 v3\nk\\=4=a\\:b\nlong=1 \\\n  2\n  \nk1=again\n",
        );
        let get = |k: &str| props.get(k).map(|p| (p.value.as_str(), p.line));
        assert_eq!(get("k1"), Some(("again", 10)));
        assert_eq!(get("k2"), Some(("v2", 4)));
        assert_eq!(get("k3"), Some(("v3", 5)));
        assert_eq!(get("k=4"), Some(("a:b", 6)));
        assert_eq!(get("long"), Some(("1 2", 7)));
    }

    #[test]
    fn light_keys_are_numbered_zero_to_seven() {
        assert!(is_light_key("light_position_0"));
        assert!(is_light_key("light_status_7"));
        assert!(!is_light_key("light_status_8"));
        assert!(!is_light_key("light_colour_1"));
    }
}
