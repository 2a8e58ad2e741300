//! Implicit polynomial surfaces typed as equations (`IMPLICIT "x^2 + y^2 + z^2 = 1" …`) or
//! named presets (`IMPLICIT torus 1 0.3 …`), placed like the heart by a position and basis.

use super::Shape;
use crate::geometry::{Aabb, DVec3, Frame, Ray};
use crate::roots::Solver;

/// Highest total degree accepted for an equation.
pub const MAX_DEGREE: usize = 16;

/// Why an equation could not be turned into a polynomial surface.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct EquationError {
    /// Byte offset of the problem within the equation text.
    pub offset: usize,
    /// Length in bytes of the offending part (at least 1 where the text has one).
    pub len: usize,
    /// What is wrong and what was expected.
    pub message: String,
}

/// The named presets and how many numeric parameters each takes, in scene order.
pub const PRESETS: &[(&str, usize)] = &[
    ("heart", 0),
    ("taubin_heart", 0),
    ("torus", 2),
    ("kummer", 1),
    ("barth_sextic", 0),
    ("clebsch", 0),
    ("chmutov", 1),
];

/// The equation text of a preset with its parameters, or a message saying what is wrong
/// with them (unknown name, wrong count, value out of range).
pub fn preset_equation(name: &str, params: &[f64]) -> Result<String, String> {
    let _ = (name, params);
    Err("presets are not implemented yet".into()) // TODO: implicit work
}

/// An implicit polynomial surface `p(x, y, z) = 0` in object space, placed by a [`Frame`],
/// optionally clipped to the object-space sphere of radius `bound` about the origin.
#[derive(Debug, Clone)]
pub struct Implicit {
    frame: Frame,
    solver: Solver,
}

impl Implicit {
    /// Parses and expands `equation` (see docs/scene-format.md) and places it with `frame`.
    /// `bound` is the object-space clip radius (`BOUND r`), `None` to derive one.
    pub fn new(equation: &str, frame: Frame, bound: Option<f64>) -> Result<Self, EquationError> {
        let _ = (equation, bound);
        Ok(Self {
            frame,
            solver: Solver::default(),
        }) // TODO: implicit work
    }

    /// The same surface, intersected with the given root-isolation strategy.
    pub fn with_solver(mut self, solver: Solver) -> Self {
        self.solver = solver;
        self
    }
}

impl Shape for Implicit {
    fn intersect(&self, _ray: &Ray, _t_min: f64, _t_max: f64) -> Option<f64> {
        None // TODO: implicit work
    }

    fn normal(&self, _p: DVec3) -> DVec3 {
        DVec3::Z // TODO: implicit work
    }

    fn bounds(&self) -> Aabb {
        self.frame.bounds_to_world(&Aabb::EVERYTHING) // TODO: implicit work
    }
}
