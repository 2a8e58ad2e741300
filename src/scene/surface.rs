//! `<surface>`: a diffuse colour or a material name, then optional properties, each read by
//! its row of [`PROPERTIES`] (keyword, usage, reader).

use std::collections::HashMap;

use super::cursor::{parse_number, Cursor, NumberError};
use super::lexer::{lex_line, Token, TokenKind};
use super::limits;
use super::words::{shorten, suggest};
use super::SceneError;
use crate::materials::Material;

type Result<T> = std::result::Result<T, SceneError>;

/// A material defined by `MATERIAL`, with its line.
pub(super) type Materials = HashMap<String, (Material, usize)>;

/// One surface property: its keyword (upper case), its usage, and the reader of its
/// arguments (the cursor is just after the keyword).
pub(super) struct Property {
    /// The keyword, upper case.
    pub keyword: &'static str,
    /// How it is written.
    pub usage: &'static str,
    /// Reads the arguments into the material.
    pub read: fn(&mut Cursor, &mut Material) -> Result<()>,
}

/// Every surface property.
pub(super) const PROPERTIES: &[Property] = &[
    Property {
        keyword: "SPECULAR",
        usage: "SPECULAR ks exponent",
        read: |cur, m| {
            m.specular = cur
                .number_in("the specular weight ks", &limits::SPECULAR_WEIGHT)?
                .0;
            m.shininess = cur
                .number_in("the specular exponent", &limits::SPECULAR_EXPONENT)?
                .0;
            Ok(())
        },
    },
    Property {
        keyword: "REFLECT",
        usage: "REFLECT kr",
        read: |cur, m| {
            m.reflect = cur
                .number_in("the reflection weight kr", &limits::WEIGHT)?
                .0;
            Ok(())
        },
    },
    Property {
        keyword: "TRANSMIT",
        usage: "TRANSMIT kt",
        read: |cur, m| {
            m.transmit = cur
                .number_in("the transmission weight kt", &limits::WEIGHT)?
                .0;
            Ok(())
        },
    },
    Property {
        keyword: "IOR",
        usage: "IOR n",
        read: |cur, m| {
            m.ior = cur.number_in("the index of refraction", &limits::IOR)?.0;
            Ok(())
        },
    },
    Property {
        keyword: "ATTENUATION",
        usage: "ATTENUATION (r, g, b)",
        read: |cur, m| {
            m.attenuation = cur.colour("the attenuation", &limits::ATTENUATION)?.v;
            Ok(())
        },
    },
    Property {
        keyword: "CHECKER",
        usage: "CHECKER (r, g, b) size",
        read: |cur, m| {
            let c = cur.colour("the checker's second colour", &limits::COLOUR)?;
            let (size, _) = cur.number_in("the checker's cell size", &limits::LENGTH)?;
            m.checker = Some((c.v, size));
            Ok(())
        },
    },
    Property {
        keyword: "INSIDE",
        usage: "INSIDE (r, g, b)",
        read: |cur, m| {
            m.inside = Some(cur.colour("the inside colour", &limits::COLOUR)?.v);
            Ok(())
        },
    },
];

/// What `<surface>` stands for in the usage lines (built from [`PROPERTIES`]).
pub(super) fn surface_usage() -> &'static str {
    static USAGE: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    USAGE.get_or_init(|| {
        let properties: Vec<&str> = PROPERTIES.iter().map(|p| p.usage).collect();
        format!(
            "<surface> is a diffuse colour (r, g, b) or the name of a MATERIAL defined \
             earlier, then optionally {}",
            properties.join(", ")
        )
    })
}

/// The property whose keyword is `word` (any case).
pub(super) fn property(word: &str) -> Option<&'static Property> {
    PROPERTIES
        .iter()
        .find(|p| p.keyword.eq_ignore_ascii_case(word))
}

/// Whether `word` (any case) is reserved in a surface: a property keyword or `BOUND`.
pub(super) fn is_reserved(word: &str) -> bool {
    word.eq_ignore_ascii_case("BOUND") || property(word).is_some()
}

/// `<surface>`: a colour or a material name, then optional properties.
pub(super) fn surface(cur: &mut Cursor, materials: &Materials) -> Result<Material> {
    cur.part_usage = Some(surface_usage());
    let m = surface_inner(cur, materials);
    cur.part_usage = None;
    m
}

fn surface_inner(cur: &mut Cursor, materials: &Materials) -> Result<Material> {
    const EXPECTED: &str = "a diffuse colour (r, g, b) or a material name";
    let Some(t) = cur.peek() else {
        if cur.keyword == "POLYGON" {
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
        TokenKind::Open => Material::diffuse(cur.colour("the diffuse colour", &limits::COLOUR)?.v),
        TokenKind::Word => {
            let word = cur.text(&t);
            if parse_number(word) != Err(NumberError::NotANumber) {
                return Err(cur.unexpected(EXPECTED));
            }
            if is_reserved(word) {
                let upper = word.to_ascii_uppercase();
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
    while let Some(prop) = cur.peek_word().and_then(property) {
        let span = cur.here();
        if seen.contains(&prop.keyword) {
            return Err(cur.fail(
                span,
                format!("{} is given twice for this surface", prop.keyword),
                "repeated property",
            ));
        }
        seen.push(prop.keyword);
        cur.pos += 1;
        (prop.read)(cur, &mut m)?;
    }
    Ok(m)
}

/// The end of a statement whose last part was a surface: explains stray words.
pub(super) fn end_after_surface(cur: &mut Cursor) -> Result<()> {
    cur.part_usage = Some(surface_usage());
    let r = end_after_surface_inner(cur);
    cur.part_usage = None;
    r
}

fn end_after_surface_inner(cur: &Cursor) -> Result<()> {
    let Some(t) = cur.peek() else {
        return Ok(());
    };
    if let Some(word) = cur.peek_word() {
        if word.eq_ignore_ascii_case("BOUND") {
            return Err(cur.fail(
                t.span,
                "BOUND applies only to IMPLICIT surfaces",
                "not allowed here",
            ));
        }
        if parse_number(word) == Err(NumberError::NotANumber) {
            let found = cur.describe(Some(&t));
            let message = format!("expected a surface property or end of line, found {found}");
            if let Some(s) = suggest(word, PROPERTIES.iter().map(|p| p.keyword)) {
                return Err(cur.fail_help(
                    t.span,
                    message,
                    "unknown surface property",
                    format!("did you mean {s}?\n{}", surface_usage()),
                ));
            }
            return Err(cur.fail(t.span, message, "unknown surface property"));
        }
    }
    if t.kind == TokenKind::Open && cur.keyword == "POLYGON" {
        return Err(cur.fail(
            t.span,
            "expected a surface property or end of line, found `(`: is there one vertex \
             more than the polygon's vertex count n?",
            "unexpected vector",
        ));
    }
    Err(cur.unexpected("a surface property or end of line"))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_surface_usage_reads_as_before() {
        assert_eq!(
            surface_usage(),
            "<surface> is a diffuse colour (r, g, b) or the name of a MATERIAL defined \
             earlier, then optionally SPECULAR ks exponent, REFLECT kr, TRANSMIT kt, IOR n, \
             ATTENUATION (r, g, b), CHECKER (r, g, b) size, INSIDE (r, g, b)"
        );
        for p in PROPERTIES {
            assert!(p.usage.starts_with(p.keyword));
        }
    }
}
