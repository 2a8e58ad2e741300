//! The camera: a pinhole (perspective) camera, or an orthographic one (parallel rays).

use crate::geometry::{Aabb, DVec3, Ray, SolidEllipsoid, LANES};

/// Why a camera is degenerate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// eye, look_at or up is NaN or infinite.
    #[error("the camera's vectors must be finite")]
    NotFinite,
    /// look_at equals eye.
    #[error("the camera looks at its own eye position: look_at must differ from eye")]
    NoViewDirection,
    /// up is zero or parallel to the view direction.
    #[error("the up vector is zero or parallel to the view direction")]
    BadUp,
    /// fov outside (0, 180).
    #[error("the field of view must be greater than 0 and less than 180 degrees, not {0}")]
    BadFov(f64),
    /// An orthographic view height that is not finite and greater than 0.
    #[error("the orthographic view height must be greater than 0, not {0}")]
    BadHeight(f64),
}

/// A camera at `eye` looking at `look_at`. A pinhole camera ([`Camera::new`]) has `fov` the
/// FULL horizontal field of view in degrees, its rays leaving `eye`; an orthographic camera
/// ([`Camera::orthographic`]) sends parallel rays along the view direction from the plane
/// through `eye` perpendicular to it, over a view `height` world units tall. Image-plane
/// coordinates run from the top-left corner `(0, 0)` to `(width, height)`; the other extent
/// follows the image's aspect ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point the camera looks at.
    pub look_at: DVec3,
    /// Approximate up direction.
    pub up: DVec3,
    /// Full horizontal field of view, degrees, in (0, 180) (of a pinhole camera; an
    /// orthographic camera keeps the one it was made with and does not use it).
    pub fov_degrees: f64,
    /// The full height of an orthographic camera's view in world units (> 0); `None` for a
    /// pinhole camera.
    orthographic_height: Option<f64>,
    forward: DVec3,
    right: DVec3,
    true_up: DVec3,
    /// `tan(fov / 2)`, the image plane's half width at unit distance.
    half_width: f64,
}

impl Camera {
    /// A camera, or why it is degenerate.
    pub fn new(
        eye: DVec3,
        look_at: DVec3,
        up: DVec3,
        fov_degrees: f64,
    ) -> Result<Self, CameraError> {
        if !(eye.is_finite() && look_at.is_finite() && up.is_finite() && fov_degrees.is_finite()) {
            return Err(CameraError::NotFinite);
        }
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            return Err(CameraError::BadFov(fov_degrees));
        }
        let forward = (look_at - eye).normalize_or_zero();
        if forward == DVec3::ZERO {
            return Err(CameraError::NoViewDirection);
        }
        let right = forward.cross(up);
        if up.length() == 0.0 || right.length() <= 1e-9 * up.length() {
            return Err(CameraError::BadUp);
        }
        let right = right.normalize();
        let true_up = right.cross(forward);
        Ok(Self {
            eye,
            look_at,
            up,
            fov_degrees,
            forward,
            right,
            true_up,
            half_width: (fov_degrees.to_radians() * 0.5).tan(),
            orthographic_height: None,
        })
    }

    /// An orthographic camera: rays parallel to `look_at − eye`, starting on the plane through
    /// `eye` perpendicular to it, over a view `height` world units tall (its width follows the
    /// image's aspect ratio); or why it is degenerate.
    pub fn orthographic(
        eye: DVec3,
        look_at: DVec3,
        up: DVec3,
        height: f64,
    ) -> Result<Self, CameraError> {
        if !(height > 0.0 && height.is_finite()) {
            return Err(CameraError::BadHeight(height));
        }
        let mut camera = Camera::new(eye, look_at, up, 40.0)?;
        camera.orthographic_height = Some(height);
        Ok(camera)
    }

    /// The same kind of camera (pinhole with its field of view, or orthographic with its
    /// height) placed at another eye, look-at point and up vector.
    pub fn moved(&self, eye: DVec3, look_at: DVec3, up: DVec3) -> Result<Self, CameraError> {
        match self.orthographic_height {
            Some(h) => Camera::orthographic(eye, look_at, up, h),
            None => Camera::new(eye, look_at, up, self.fov_degrees),
        }
    }

    /// The full height of the view in world units of an orthographic camera; `None` for a
    /// pinhole camera.
    pub fn orthographic_height(&self) -> Option<f64> {
        self.orthographic_height
    }

    /// Unit vector from the eye toward `look_at`.
    pub fn forward(&self) -> DVec3 {
        self.forward
    }

    /// The primary ray through image-plane point `(x, y)` (pixels; `(0,0)` the top-left corner
    /// of the image, `(x + 0.5, y + 0.5)` the centre of pixel `(x, y)`) of a `width × height`
    /// image. The direction is unit length (for an orthographic camera, the view direction).
    pub fn ray(&self, x: f64, y: f64, width: u32, height: u32) -> Ray {
        let plane = self.plane(width, height);
        if self.orthographic_height.is_some() {
            return Ray::new(self.on_plane(plane.sx(x), plane.sy(y)), self.forward);
        }
        Ray::new(self.eye, self.through(plane.sx(x), plane.sy(y)).normalize())
    }

    /// The image plane of a `width × height` image: at unit distance for a pinhole camera, in
    /// world units on the eye's plane for an orthographic one.
    fn plane(&self, width: u32, height: u32) -> ImagePlane {
        let (w, h) = (width as f64, height as f64);
        match self.orthographic_height {
            Some(view_height) => ImagePlane {
                half_width: 0.5 * view_height * w / h,
                half_height: 0.5 * view_height,
                width: w,
                height: h,
            },
            None => ImagePlane {
                half_width: self.half_width,
                half_height: self.half_width * h / w,
                width: w,
                height: h,
            },
        }
    }

    /// An orthographic ray's origin: the point `(sx, sy)` world units right of and above the
    /// eye on the plane perpendicular to the view.
    #[inline]
    fn on_plane(&self, sx: f64, sy: f64) -> DVec3 {
        self.eye + sx * self.right + sy * self.true_up
    }

    /// The direction (not normalised) from the eye through the image-plane point `(sx, sy)`
    /// at unit distance.
    #[inline]
    fn through(&self, sx: f64, sy: f64) -> DVec3 {
        self.forward + sx * self.right + sy * self.true_up
    }

    /// [`Camera::ray`] through [`LANES`] image-plane points `(xs[i], ys[i])` at once: lane `i`
    /// is exactly `self.ray(xs[i], ys[i], width, height)`, bit for bit. The lanes' divisions
    /// and square roots are independent of each other, which lets them run side by side.
    #[inline]
    pub fn rays_lanes(
        &self,
        xs: [f64; LANES],
        ys: [f64; LANES],
        width: u32,
        height: u32,
    ) -> [Ray; LANES] {
        let plane = self.plane(width, height);
        if self.orthographic_height.is_some() {
            return std::array::from_fn(|i| {
                Ray::new(
                    self.on_plane(plane.sx(xs[i]), plane.sy(ys[i])),
                    self.forward,
                )
            });
        }
        // Each step lane by lane over arrays, in the operation order of `ray` (and of glam's
        // `normalize`: the reciprocal of the square root of the dot product, then a product).
        let dirs: [DVec3; LANES] =
            std::array::from_fn(|i| self.through(plane.sx(xs[i]), plane.sy(ys[i])));
        let lengths: [f64; LANES] = std::array::from_fn(|i| dirs[i].dot(dirs[i]).sqrt());
        let recips: [f64; LANES] = std::array::from_fn(|i| 1.0 / lengths[i]);
        std::array::from_fn(|i| Ray::new(self.eye, dirs[i] * recips[i]))
    }

    /// A rectangle of the image plane of a `width × height` image (pixels, as [`Camera::ray`]
    /// takes them) that holds every point whose primary ray meets `bounds`, with a margin of
    /// a few pixels for rounding; `None` when part of the box is not in front of the eye (or
    /// is not finite), as the primary rays of any point may then meet it.
    pub fn image_rect(&self, bounds: &Aabb, width: u32, height: u32) -> Option<ImageRect> {
        if bounds.min.cmpgt(bounds.max).any() {
            return Some(ImageRect::NOTHING);
        }
        self.hull_rect(&bounds.corners(), width, height)
    }

    /// [`Camera::image_rect`] for the convex hull of `points` (the corners of a
    /// [`crate::geometry::Hexahedron`], say): every point whose primary ray meets the hull lies in the rectangle; `None` when
    /// a point is not in front of the eye (or is not finite). An orthographic camera projects
    /// along parallel lines, so any point will do there (a point behind its plane is only
    /// never seen).
    pub fn hull_rect(&self, points: &[DVec3], width: u32, height: u32) -> Option<ImageRect> {
        let plane = self.plane(width, height);
        let mut rect = ImageRect::NOTHING;
        for &c in points {
            let v = c - self.eye;
            if self.orthographic_height.is_some() {
                // The parallel projection of the hull is the hull of its points' projections.
                let x = plane.column(v.dot(self.right));
                let y = plane.row(v.dot(self.true_up));
                if !(x.is_finite() && y.is_finite()) {
                    return None;
                }
                rect = rect.union(ImageRect {
                    x: (x, x),
                    y: (y, y),
                });
                continue;
            }
            let depth = v.dot(self.forward);
            // Well in front of the eye: the projection of the hull is then the hull of its
            // points' projections (a convex set seen from outside its half-space).
            let in_front = depth > 1e-9 * v.length();
            if !in_front || !v.is_finite() {
                return None;
            }
            // The image point whose ray passes through the point: the inverse of `ray`.
            let x = plane.column(v.dot(self.right) / depth);
            let y = plane.row(v.dot(self.true_up) / depth);
            if !(x.is_finite() && y.is_finite()) {
                return None;
            }
            rect = rect.union(ImageRect {
                x: (x, x),
                y: (y, y),
            });
        }
        Some(rect.padded())
    }

    /// The outline of a solid ellipsoid's image on the image plane of a `width × height`
    /// image (an ellipse), to find which points of each row see it
    /// ([`EllipseImage::row_span`]) or the rectangle around it ([`EllipseImage::rect`]);
    /// `None` when part of the ellipsoid is not in front of the eye of a pinhole camera (or
    /// it is not finite, or flat).
    pub fn ellipsoid_image(
        &self,
        e: &SolidEllipsoid,
        width: u32,
        height: u32,
    ) -> Option<EllipseImage> {
        if self.orthographic_height.is_none() {
            // All of it in front: its nearest depth, (c − eye)·forward − |axesᵀ·forward|, > 0.
            let depth = (e.centre - self.eye).dot(self.forward);
            let in_front =
                depth - (e.axes.transpose() * self.forward).length() > 1e-9 * depth.abs();
            if !in_front {
                return None;
            }
        }
        if !e.centre.is_finite() {
            return None;
        }
        let inv = e.axes.inverse();
        if !inv.is_finite() {
            return None;
        }
        if self.orthographic_height.is_some() {
            // The line from eye + sx·right + sy·up along forward, in the unit ball's
            // coordinates: (o + sx·R + sy·T) + λ·F. It meets the ball iff
            // D = (O·F)² − |F|²(|O|² − 1) ≥ 0, again a quadratic form in (sx, sy).
            let o = inv * (self.eye - e.centre);
            let (f, r, t) = (inv * self.forward, inv * self.right, inv * self.true_up);
            let ff = f.dot(f);
            let (a0, a1, a2) = (o.dot(f), r.dot(f), t.dot(f));
            let p = [
                [a1 * a1 - ff * r.dot(r), a1 * a2 - ff * r.dot(t)],
                [a1 * a2 - ff * r.dot(t), a2 * a2 - ff * t.dot(t)],
            ];
            let q = [a0 * a1 - ff * o.dot(r), a0 * a2 - ff * o.dot(t)];
            let r0 = a0 * a0 - ff * (o.length_squared() - 1.0);
            return EllipseImage::from_form(p, q, r0, self.plane(width, height));
        }
        // In the unit ball's coordinates the ray from the eye towards f + sx·r + sy·t is
        // o + λ·(F + sx·R + sy·T); it meets the ball iff D = (o·w)² − |w|²(|o|² − 1) ≥ 0,
        // a quadratic form in (sx, sy): sᵀPs + 2qᵀs + r₀.
        let o = inv * (self.eye - e.centre);
        let (f, r, t) = (inv * self.forward, inv * self.right, inv * self.true_up);
        let k = o.length_squared() - 1.0;
        let (a0, a1, a2) = (o.dot(f), o.dot(r), o.dot(t));
        let p = [
            [a1 * a1 - k * r.dot(r), a1 * a2 - k * r.dot(t)],
            [a1 * a2 - k * r.dot(t), a2 * a2 - k * t.dot(t)],
        ];
        let q = [a0 * a1 - k * f.dot(r), a0 * a2 - k * f.dot(t)];
        let r0 = a0 * a0 - k * f.dot(f);
        EllipseImage::from_form(p, q, r0, self.plane(width, height))
    }
}

impl EllipseImage {
    /// The image where D(s) = sᵀPs + 2qᵀs + r₀ ≥ 0, the image-plane points `s = (sx, sy)`
    /// whose rays meet the ellipsoid; `None` unless it is a bounded ellipse.
    fn from_form(p: [[f64; 2]; 2], q: [f64; 2], r0: f64, plane: ImagePlane) -> Option<Self> {
        // D = δ − (s − c)ᵀG(s − c) with G = −P (positive definite for a bounded image).
        let g = [[-p[0][0], -p[0][1]], [-p[1][0], -p[1][1]]];
        let det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
        if !(g[0][0] > 0.0 && det > 0.0 && det.is_finite()) {
            return None;
        }
        let g_inv = [
            [g[1][1] / det, -g[0][1] / det],
            [-g[1][0] / det, g[0][0] / det],
        ];
        let c = [
            g_inv[0][0] * q[0] + g_inv[0][1] * q[1],
            g_inv[1][0] * q[0] + g_inv[1][1] * q[1],
        ];
        let delta = r0 + q[0] * c[0] + q[1] * c[1];
        if !(delta > 0.0 && delta.is_finite()) {
            return None;
        }
        Some(EllipseImage {
            centre: c,
            g,
            delta,
            // The ellipse reaches ±√(δ·(G⁻¹)₁₁) in sx and ±√(δ·(G⁻¹)₂₂) in sy; its rightmost
            // point is c + G⁻¹·eₓ·√(δ / (G⁻¹)₁₁).
            u_reach: (delta * g_inv[0][0]).sqrt(),
            v_reach: (delta * g_inv[1][1]).sqrt(),
            sy_of_rightmost: g_inv[1][0] * (delta / g_inv[0][0]).sqrt(),
            plane,
        })
    }
}

/// The image of a solid ellipsoid (see [`Camera::ellipsoid_image`]): the image-plane
/// points `(sx, sy)` (at unit distance) with `(s − c)ᵀG(s − c) ≤ δ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipseImage {
    centre: [f64; 2],
    g: [[f64; 2]; 2],
    delta: f64,
    /// Half the ellipse's extent in sx and in sy.
    u_reach: f64,
    v_reach: f64,
    sy_of_rightmost: f64,
    plane: ImagePlane,
}

/// The image plane of a `width × height` image: pixel coordinates (as [`Camera::ray`] takes
/// them) against offsets `(sx, sy)` along the camera's right and up vectors at unit distance.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ImagePlane {
    /// The plane's half extents at unit distance.
    half_width: f64,
    half_height: f64,
    /// The image's size in pixels.
    width: f64,
    height: f64,
}

impl ImagePlane {
    /// Column `x` (pixels) as the offset `sx`.
    #[inline]
    fn sx(&self, x: f64) -> f64 {
        (2.0 * x / self.width - 1.0) * self.half_width
    }

    /// Row `y` (pixels) as the offset `sy` (it falls as `y` grows).
    #[inline]
    fn sy(&self, y: f64) -> f64 {
        (1.0 - 2.0 * y / self.height) * self.half_height
    }

    /// The offset `sx` as a column, in pixels.
    fn column(&self, sx: f64) -> f64 {
        (sx / self.half_width + 1.0) * 0.5 * self.width
    }

    /// The offset `sy` as a row, in pixels.
    fn row(&self, sy: f64) -> f64 {
        (1.0 - sy / self.half_height) * 0.5 * self.height
    }
}

impl EllipseImage {
    /// A rectangle of the image plane (pixels) that holds every point whose primary ray meets
    /// the ellipsoid, with the margin of [`Camera::image_rect`].
    pub fn rect(&self) -> ImageRect {
        let [cx, cy] = self.centre;
        ImageRect {
            x: (
                self.plane.column(cx - self.u_reach),
                self.plane.column(cx + self.u_reach),
            ),
            y: (
                self.plane.row(cy + self.v_reach),
                self.plane.row(cy - self.v_reach),
            ),
        }
        .padded()
    }

    /// The columns `(x0, x1)` (pixels, as [`Camera::ray`] takes them) that hold every point
    /// of the rows `y0 ≤ y ≤ y1` whose primary ray meets the ellipsoid, with the margin of
    /// [`Camera::image_rect`] on every side; `None` when none does.
    pub fn row_span(&self, y0: f64, y1: f64) -> Option<(f64, f64)> {
        // Rows widened by the margin, as image-plane offsets from the centre (sy falls as y
        // grows).
        let plane = &self.plane;
        let (v_lo, v_hi) = (
            plane.sy(y1 + margin(y1)) - self.centre[1],
            plane.sy(y0 - margin(y0)) - self.centre[1],
        );
        // The ellipse's rows: G₁₁u² + 2G₁₂uv + G₂₂v² ≤ δ has a u for |v| ≤ v_reach.
        let [[g11, g12], [_, g22]] = self.g;
        let (lo, hi) = (v_lo.max(-self.v_reach), v_hi.min(self.v_reach));
        let some_row = lo <= hi;
        if !some_row {
            return None;
        }
        // u at the edge of the ellipse on row v: (−G₁₂v ± √(G₁₂²v² − G₁₁(G₂₂v² − δ))) / G₁₁;
        // the right edge is concave in v, largest at the rightmost point's v, the left edge
        // smallest at the leftmost point's (−that).
        let edge = |v: f64, side: f64| {
            let root = (g12 * g12 * v * v - g11 * (g22 * v * v - self.delta))
                .max(0.0)
                .sqrt();
            (-g12 * v + side * root) / g11
        };
        let right = edge(self.sy_of_rightmost.clamp(lo, hi), 1.0);
        let left = edge((-self.sy_of_rightmost).clamp(lo, hi), -1.0);
        let (x0, x1) = (
            self.plane.column(left + self.centre[0]),
            self.plane.column(right + self.centre[0]),
        );
        (x0.is_finite() && x1.is_finite()).then(|| (x0 - margin(x0), x1 + margin(x1)))
    }
}

/// The margin by which the image rectangles and row spans are widened for rounding at a
/// coordinate `v` (pixels): two pixels and 1e-9 of `v` (rounding in [`Camera::ray`], the
/// bound tests and the projections is far below a pixel).
fn margin(v: f64) -> f64 {
    2.0 + 1e-9 * v.abs()
}

/// A rectangle of the image plane, in pixels (see [`Camera::image_rect`]): the points
/// `x.0 ≤ x ≤ x.1`, `y.0 ≤ y ≤ y.1`; empty when `x.0 > x.1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageRect {
    /// Smallest and largest column coordinate.
    pub x: (f64, f64),
    /// Smallest and largest row coordinate.
    pub y: (f64, f64),
}

impl ImageRect {
    /// The rectangle that holds no point; the identity of [`ImageRect::union`].
    pub const NOTHING: ImageRect = ImageRect {
        x: (f64::INFINITY, f64::NEG_INFINITY),
        y: (f64::INFINITY, f64::NEG_INFINITY),
    };

    /// The rectangle widened by the [`margin`] for rounding on every side.
    fn padded(self) -> ImageRect {
        let pad = |(lo, hi): (f64, f64)| {
            let m = margin(lo.abs().max(hi.abs()));
            (lo - m, hi + m)
        };
        ImageRect {
            x: pad(self.x),
            y: pad(self.y),
        }
    }

    /// The smallest rectangle holding both.
    pub fn union(self, other: ImageRect) -> ImageRect {
        ImageRect {
            x: (self.x.0.min(other.x.0), self.x.1.max(other.x.1)),
            y: (self.y.0.min(other.y.0), self.y.1.max(other.y.1)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Frame;
    use crate::testing::uniform_stream;

    /// A camera a few units up the z axis, looking near the origin, tilted, with a field of
    /// view of 20–120° (or, `orthographic`, a view 1–7 units tall).
    fn random_camera(next: &mut impl FnMut() -> f64, orthographic: bool) -> Camera {
        let eye = DVec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, 6.0 + next());
        let look = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
        let up = DVec3::new(next() - 0.5, 1.0, 0.0);
        let size = next();
        if orthographic {
            Camera::orthographic(eye, look, up, 1.0 + 6.0 * size).unwrap()
        } else {
            Camera::new(eye, look, up, 20.0 + 100.0 * size).unwrap()
        }
    }

    /// A random ellipsoid near the origin (three random conjugate semi-axes of up to about
    /// 1.7), or `None` when it is nearly flat.
    fn random_ellipsoid(next: &mut impl FnMut() -> f64) -> Option<SolidEllipsoid> {
        let mut axis = || DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 2.0;
        let axes = glam::DMat3::from_cols(axis(), axis(), axis());
        let centre = DVec3::new(next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0);
        (axes.determinant().abs() >= 1e-3).then_some(SolidEllipsoid { centre, axes })
    }

    #[test]
    fn rays_in_lanes_are_the_single_rays_bit_for_bit() {
        for orthographic in [false, true] {
            rays_in_lanes_are_the_single_rays_bit_for_bit_for(orthographic);
        }
    }

    fn rays_in_lanes_are_the_single_rays_bit_for_bit_for(orthographic: bool) {
        let mut next = uniform_stream(0x5eed_cafe);
        for _ in 0..500 {
            let camera = random_camera(&mut next, orthographic);
            let (width, height) = (1 + (next() * 2000.0) as u32, 1 + (next() * 2000.0) as u32);
            let xs: [f64; LANES] = std::array::from_fn(|_| next() * width as f64);
            let ys: [f64; LANES] = std::array::from_fn(|_| next() * height as f64);
            let lanes = camera.rays_lanes(xs, ys, width, height);
            for i in 0..LANES {
                let single = camera.ray(xs[i], ys[i], width, height);
                assert_eq!(lanes[i].origin.to_array(), single.origin.to_array());
                let bits = |d: DVec3| d.to_array().map(f64::to_bits);
                assert_eq!(bits(lanes[i].dir), bits(single.dir), "lane {i}");
            }
        }
    }

    /// Whether the image point `(x, y)` is in the rectangle.
    fn holds(rect: &ImageRect, x: f64, y: f64) -> bool {
        (rect.x.0..=rect.x.1).contains(&x) && (rect.y.0..=rect.y.1).contains(&y)
    }

    /// Whether the ray meets the solid ellipsoid at some `t > 0`: `|o + t·d|² = 1` in the
    /// unit ball's coordinates has a root there.
    fn ray_meets(e: &SolidEllipsoid, ray: &Ray) -> bool {
        let inv = e.axes.inverse();
        let (o, d) = (inv * (ray.origin - e.centre), inv * ray.dir);
        let (a, b, c) = (d.length_squared(), o.dot(d), o.length_squared() - 1.0);
        let disc = b * b - a * c;
        disc >= 0.0 && -b + disc.sqrt() > 0.0
    }

    /// The image point (pixels of a `w × h` image) whose ray passes through `p`, in front.
    fn image_point(cam: &Camera, p: DVec3, w: u32, h: u32) -> (f64, f64) {
        let v = p - cam.eye;
        let plane = cam.plane(w, h);
        let (u, t) = (v.dot(cam.right), v.dot(cam.true_up));
        if cam.orthographic_height.is_some() {
            return (plane.column(u), plane.row(t));
        }
        let depth = v.dot(cam.forward);
        (plane.column(u / depth), plane.row(t / depth))
    }

    #[test]
    fn an_orthographic_camera_sends_parallel_rays_over_its_height() {
        let eye = DVec3::new(1.0, 2.0, 3.0);
        let cam = Camera::orthographic(eye, DVec3::new(1.0, 12.0, 3.0), DVec3::Z, 4.0).unwrap();
        assert_eq!(cam.orthographic_height(), Some(4.0));
        let centre = cam.ray(50.0, 25.0, 100, 50);
        assert_eq!(centre.origin, eye);
        assert_eq!(centre.dir, DVec3::Y);
        // 4 units tall, so 8 wide at 2:1; +x is right and +z up looking along +y.
        let top_left = cam.ray(0.0, 0.0, 100, 50);
        assert!((top_left.origin - (eye + DVec3::new(-4.0, 0.0, 2.0))).length() < 1e-12);
        assert_eq!(top_left.dir, DVec3::Y);
        let bottom_right = cam.ray(100.0, 50.0, 100, 50);
        assert!((bottom_right.origin - (eye + DVec3::new(4.0, 0.0, -2.0))).length() < 1e-12);
        // Moved, it stays orthographic with its height; a bad height is refused.
        let moved = cam.moved(DVec3::ZERO, DVec3::X, DVec3::Z).unwrap();
        assert_eq!(moved.orthographic_height(), Some(4.0));
        assert_eq!(moved.ray(50.0, 25.0, 100, 50).dir, DVec3::X);
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                Camera::orthographic(eye, DVec3::ZERO, DVec3::Z, bad),
                Err(CameraError::BadHeight(_))
            ));
        }
    }

    #[test]
    fn centre_ray_looks_forward_and_edges_span_the_fov() {
        let eye = DVec3::new(1.0, 2.0, 3.0);
        let cam = Camera::new(eye, DVec3::new(1.0, 12.0, 3.0), DVec3::Z, 90.0).unwrap();
        let centre = cam.ray(50.0, 25.0, 100, 50);
        assert_eq!(centre.origin, eye);
        assert!((centre.dir - DVec3::Y).length() < 1e-12);
        // The left and right edges are 45° off axis (full horizontal fov 90°); +x is right
        // when looking along +y with +z up.
        let left = cam.ray(0.0, 25.0, 100, 50).dir;
        let right = cam.ray(100.0, 25.0, 100, 50).dir;
        assert!((left - DVec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-12);
        assert!((right - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-12);
        // The top edge follows the aspect ratio: tan = 0.5 above the axis.
        let top = cam.ray(50.0, 0.0, 100, 50).dir;
        assert!((top - DVec3::new(0.0, 1.0, 0.5).normalize()).length() < 1e-12);
    }

    #[test]
    fn no_ray_from_outside_a_box_or_parallelepiped_image_rect_meets_it() {
        for orthographic in [false, true] {
            no_ray_from_outside_a_box_or_parallelepiped_image_rect_meets_it_for(orthographic);
        }
    }

    fn no_ray_from_outside_a_box_or_parallelepiped_image_rect_meets_it_for(orthographic: bool) {
        // Small deterministic generator: boxes in front of tilted cameras, then image points
        // all over (and beyond) the image.
        let mut next = uniform_stream(0x2545_f491_4f6c_dd1du64);
        let (w, h) = (64, 48);
        let (mut outside, mut skewed_outside) = (0, 0);
        for _ in 0..300 {
            let cam = random_camera(&mut next, orthographic);
            let eye = cam.eye;
            let centre = DVec3::new(next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0);
            let half = DVec3::new(next(), next(), next()) * 1.5 + DVec3::splat(0.01);
            let bounds = Aabb {
                min: centre - half,
                max: centre + half,
            };
            let Some(rect) = cam.image_rect(&bounds, w, h) else {
                continue;
            };
            // The box's centre is seen inside the rectangle.
            let (cx, cy) = image_point(&cam, centre, w, h);
            assert!(holds(&rect, cx, cy), "({cx}, {cy}) not in {rect:?}");
            if !orthographic {
                let v = centre - eye;
                let dir = v / v.length();
                assert!(bounds
                    .clip(&Ray::new(eye, dir), 0.0, f64::INFINITY)
                    .is_some());
            }
            for _ in 0..200 {
                let (x, y) = (
                    next() * 1.4 * w as f64 - 0.2 * w as f64,
                    next() * 1.4 * h as f64 - 0.2 * h as f64,
                );
                if holds(&rect, x, y) {
                    continue;
                }
                outside += 1;
                let ray = cam.ray(x, y, w, h);
                assert!(
                    bounds.clip(&ray, 0.0, f64::INFINITY).is_none(),
                    "({x}, {y}) is outside {rect:?} but its ray meets {bounds:?}"
                );
            }
            // The same box skewed and moved by a frame: a parallelepiped, its hull's rectangle.
            let mut axis = || DVec3::new(next(), next(), next()) * 1.2 - DVec3::splat(0.6);
            let (u, v, w_axis) = (DVec3::X + axis(), DVec3::Y + axis(), DVec3::Z + axis());
            let Ok(frame) = Frame::new(axis(), u, v, w_axis) else {
                continue;
            };
            let cell = frame.box_to_world(&bounds);
            let Some(rect) = cam.hull_rect(&cell.corners, w, h) else {
                continue;
            };
            for _ in 0..200 {
                let (x, y) = (
                    next() * 1.4 * w as f64 - 0.2 * w as f64,
                    next() * 1.4 * h as f64 - 0.2 * h as f64,
                );
                if holds(&rect, x, y) {
                    continue;
                }
                skewed_outside += 1;
                let ray = frame.ray_to_object(&cam.ray(x, y, w, h));
                assert!(
                    bounds.clip(&ray, 0.0, f64::INFINITY).is_none(),
                    "({x}, {y}) is outside {rect:?} but its ray meets {cell:?}"
                );
            }
        }
        assert!(
            outside > 10_000 && skewed_outside > 10_000,
            "the rectangles leave out most points: {outside}, {skewed_outside}"
        );
        // A box around or behind the eye has no rectangle; an empty one holds nothing.
        let cam = Camera::new(DVec3::ZERO, DVec3::X, DVec3::Z, 40.0).unwrap();
        let around = Aabb {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        };
        assert_eq!(cam.image_rect(&around, w, h), None);
        let behind = Aabb {
            min: DVec3::new(-3.0, -1.0, -1.0),
            max: DVec3::new(-2.0, 1.0, 1.0),
        };
        assert_eq!(cam.image_rect(&behind, w, h), None);
        let rect = cam.image_rect(&Aabb::EMPTY, w, h).unwrap();
        assert!(rect.x.0 > rect.x.1 && rect.y.0 > rect.y.1);
    }

    #[test]
    fn no_ray_from_outside_an_ellipsoid_image_rect_meets_the_ellipsoid() {
        for orthographic in [false, true] {
            no_ray_from_outside_an_ellipsoid_image_rect_meets_the_ellipsoid_for(orthographic);
        }
    }

    fn no_ray_from_outside_an_ellipsoid_image_rect_meets_the_ellipsoid_for(orthographic: bool) {
        let mut next = uniform_stream(0x9e37_79b9_7f4a_7c15u64);
        let (w, h) = (640, 480);
        let (mut outside, mut tight) = (0, 0);
        for _ in 0..300 {
            let cam = random_camera(&mut next, orthographic);
            let Some(e) = random_ellipsoid(&mut next) else {
                continue;
            };
            let SolidEllipsoid { centre, axes } = e;
            let Some(rect) = cam.ellipsoid_image(&e, w, h).map(|i| i.rect()) else {
                continue;
            };
            let meets = |ray: &Ray| ray_meets(&e, ray);
            // Every point of the ellipsoid's surface is inside the rectangle, and some are
            // within a few pixels of each side (the rectangle is tight).
            let mut reach = ImageRect::NOTHING;
            for _ in 0..400 {
                let u = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                let (x, y) = image_point(&cam, centre + axes * u, w, h);
                assert!(holds(&rect, x, y), "({x}, {y}) not in {rect:?}");
                reach = reach.union(ImageRect {
                    x: (x, x),
                    y: (y, y),
                });
            }
            if rect.x.1 - reach.x.1 < 3.0 && reach.x.0 - rect.x.0 < 3.0 {
                tight += 1;
            }
            for _ in 0..200 {
                let x = next() * 1.4 * w as f64 - 0.2 * w as f64;
                let y = next() * 1.4 * h as f64 - 0.2 * h as f64;
                if holds(&rect, x, y) {
                    continue;
                }
                outside += 1;
                let ray = cam.ray(x, y, w, h);
                assert!(
                    !meets(&ray),
                    "({x}, {y}) is outside {rect:?} but its ray meets {e:?}"
                );
            }
        }
        assert!(
            outside > 10_000,
            "the rectangles leave out most points: {outside}"
        );
        assert!(
            tight > 100,
            "the rectangles are close to the ellipsoids: {tight}"
        );
        // An ellipsoid around the eye has no rectangle (and no image).
        let cam = Camera::new(DVec3::ZERO, DVec3::X, DVec3::Z, 40.0).unwrap();
        let around = SolidEllipsoid::axis_aligned(DVec3::new(0.5, 0.0, 0.0), DVec3::ONE);
        assert_eq!(cam.ellipsoid_image(&around, w, h), None);
    }

    #[test]
    fn no_ray_from_outside_an_ellipsoid_row_span_meets_the_ellipsoid() {
        for orthographic in [false, true] {
            no_ray_from_outside_an_ellipsoid_row_span_meets_the_ellipsoid_for(orthographic);
        }
    }

    fn no_ray_from_outside_an_ellipsoid_row_span_meets_the_ellipsoid_for(orthographic: bool) {
        let mut next = uniform_stream(0x1234_5678_9abc_def1u64);
        let (w, h) = (320, 240);
        let (mut outside, mut images, mut narrower) = (0, 0, 0);
        for _ in 0..200 {
            let cam = random_camera(&mut next, orthographic);
            let Some(e) = random_ellipsoid(&mut next) else {
                continue;
            };
            let SolidEllipsoid { centre, axes } = e;
            let Some(image) = cam.ellipsoid_image(&e, w, h) else {
                continue;
            };
            images += 1;
            let rect = image.rect();
            let meets = |ray: &Ray| ray_meets(&e, ray);
            for _ in 0..300 {
                // A band of one row (or of a few), and a point in it.
                let y0 = (next() * 1.4 * h as f64 - 0.2 * h as f64).floor();
                let y1 = y0 + if next() < 0.5 { 1.0 } else { 16.0 };
                let span = image.row_span(y0, y1);
                if let Some((x0, x1)) = span {
                    assert!(
                        x0 >= rect.x.0 - 1e-6 && x1 <= rect.x.1 + 1e-6,
                        "{span:?} {rect:?}"
                    );
                    if x1 - x0 < rect.x.1 - rect.x.0 - 1.0 {
                        narrower += 1;
                    }
                }
                let x = next() * 1.4 * w as f64 - 0.2 * w as f64;
                let y = y0 + (y1 - y0) * next();
                if span.is_some_and(|(x0, x1)| x >= x0 && x <= x1) {
                    continue;
                }
                outside += 1;
                let ray = cam.ray(x, y, w, h);
                assert!(
                    !meets(&ray),
                    "({x}, {y}) is outside {span:?} but its ray meets {e:?}"
                );
            }
            // The points of the outline are inside their row's span.
            for _ in 0..300 {
                let u = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                let (x, y) = image_point(&cam, centre + axes * u, w, h);
                let (x0, x1) = image.row_span(y.floor(), y.floor() + 1.0).unwrap();
                assert!(
                    x >= x0 && x <= x1,
                    "({x}, {y}) outside its row's span ({x0}, {x1})"
                );
            }
        }
        assert!(images > 100, "{images}");
        assert!(outside > 10_000, "{outside}");
        assert!(
            narrower > 10_000,
            "the spans are no tighter than the rectangle: {narrower}"
        );
    }

    #[test]
    fn rejects_degenerate_cameras() {
        let e = DVec3::ZERO;
        assert_eq!(
            Camera::new(e, e, DVec3::Z, 40.0),
            Err(CameraError::NoViewDirection)
        );
        assert_eq!(
            Camera::new(e, DVec3::Z, DVec3::Z, 40.0),
            Err(CameraError::BadUp)
        );
        assert_eq!(
            Camera::new(e, DVec3::X, DVec3::Z, 180.0),
            Err(CameraError::BadFov(180.0))
        );
    }
}
