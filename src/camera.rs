//! The pinhole camera.

use crate::geometry::{DVec3, Ray};

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
}

/// A pinhole camera at `eye` looking at `look_at`, with `fov` the FULL horizontal field of view
/// in degrees. Image-plane coordinates run from the top-left corner `(0, 0)` to
/// `(width, height)`; the vertical extent follows the image's aspect ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point the camera looks at.
    pub look_at: DVec3,
    /// Approximate up direction.
    pub up: DVec3,
    /// Full horizontal field of view, degrees, in (0, 180).
    pub fov_degrees: f64,
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
        })
    }

    /// Unit vector from the eye toward `look_at`.
    pub fn forward(&self) -> DVec3 {
        self.forward
    }

    /// The primary ray through image-plane point `(x, y)` (pixels; `(0,0)` the top-left corner
    /// of the image, `(x + 0.5, y + 0.5)` the centre of pixel `(x, y)`) of a `width × height`
    /// image. The direction is unit length.
    pub fn ray(&self, x: f64, y: f64, width: u32, height: u32) -> Ray {
        let half_w = self.half_width;
        let half_h = half_w * height as f64 / width as f64;
        let sx = (2.0 * x / width as f64 - 1.0) * half_w;
        let sy = (1.0 - 2.0 * y / height as f64) * half_h;
        let dir = (self.forward + sx * self.right + sy * self.true_up).normalize();
        Ray::new(self.eye, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
