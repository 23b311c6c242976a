//! Cameras: perspective (glTF yfov) and orthographic, looking down their local −Z.

use crate::geometry::Ray;
use crate::math::{Affine3A, Vec2, Vec3};
use crate::scene::desc::Projection;

#[derive(Clone, Debug)]
pub struct Camera {
    /// Rigid `world_from_camera` (scale removed).
    world_from_camera: Affine3A,
    projection: Projection,
    pub width: u32,
    pub height: u32,
    /// Derived once from the two fields above (private, so they cannot drift apart):
    /// stbpt projects a point per landing, and the inverse and the tangent recomputed per
    /// call were ≈ 3 % of its serving in `perf`. The same expressions as before, so the
    /// same bits.
    camera_from_world: Affine3A,
    /// `tan(yfov / 2)` of a perspective camera (0 for an orthographic one).
    tan_half_yfov: f32,
    /// Unit viewing direction (camera −Z in world space).
    forward: Vec3,
}

impl Camera {
    /// Camera for a `width`×`height` image; the image aspect ratio is the render
    /// resolution's (a glTF `aspectRatio` that differs only changes the horizontal field).
    pub fn new(
        world_from_camera: Affine3A,
        projection: Projection,
        width: u32,
        height: u32,
    ) -> Self {
        let (_, rot, trans) = world_from_camera.to_scale_rotation_translation();
        let world_from_camera = Affine3A::from_rotation_translation(rot, trans);
        Camera {
            world_from_camera,
            projection,
            width,
            height,
            camera_from_world: world_from_camera.inverse(),
            tan_half_yfov: match projection {
                Projection::Perspective { yfov, .. } => (0.5 * yfov).tan(),
                Projection::Orthographic { .. } => 0.0,
            },
            forward: world_from_camera.transform_vector3(-Vec3::Z).normalize(),
        }
    }

    /// Rigid `world_from_camera` (scale removed).
    pub fn world_from_camera(&self) -> Affine3A {
        self.world_from_camera
    }

    pub fn projection(&self) -> Projection {
        self.projection
    }

    pub fn position(&self) -> Vec3 {
        self.world_from_camera.translation.into()
    }

    /// Ray through raster position `raster` (pixels, (0,0) top-left corner of the image).
    pub fn generate_ray(&self, raster: Vec2) -> Ray {
        let (w, h) = (self.width as f32, self.height as f32);
        // Normalised device coordinates in [-1, 1], +y up.
        let ndc = Vec2::new(2.0 * raster.x / w - 1.0, 1.0 - 2.0 * raster.y / h);
        let aspect = w / h;
        match self.projection {
            Projection::Perspective { .. } => {
                let th = self.tan_half_yfov;
                let d = Vec3::new(ndc.x * th * aspect, ndc.y * th, -1.0).normalize();
                Ray::new(self.position(), self.world_from_camera.transform_vector3(d))
            }
            Projection::Orthographic { xmag: _, ymag } => {
                let o = Vec3::new(ndc.x * ymag * aspect, ndc.y * ymag, 0.0);
                Ray::new(
                    self.world_from_camera.transform_point3(o),
                    self.world_from_camera.transform_vector3(-Vec3::Z),
                )
            }
        }
    }

    /// Raster position of world point `p`, if it is in front of the camera and inside the image.
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        let c = self.camera_from_world.transform_point3(p);
        let (w, h) = (self.width as f32, self.height as f32);
        let aspect = w / h;
        let ndc = match self.projection {
            Projection::Perspective { .. } => {
                if c.z >= 0.0 {
                    return None;
                }
                let th = self.tan_half_yfov;
                Vec2::new(c.x / (-c.z * th * aspect), c.y / (-c.z * th))
            }
            Projection::Orthographic { ymag, .. } => Vec2::new(c.x / (ymag * aspect), c.y / ymag),
        };
        let r = Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h);
        (r.x >= 0.0 && r.y >= 0.0 && r.x < w && r.y < h).then_some(r)
    }
}

/// Importance arriving at a point from a pinhole camera: the camera side of a connection
/// made from a light subpath (pbrt-v4 `Camera::SampleWi`).
#[derive(Clone, Copy, Debug)]
pub struct CameraWiSample {
    /// Unit direction from the reference point towards the camera.
    pub wi: Vec3,
    /// Importance We of the camera ray through the reference point (see [`Camera::we`]).
    pub we: f32,
    /// Density of the camera position as seen from the reference point, w.r.t. solid angle
    /// at the reference point: d²/cos θ (the pinhole is a delta in position; its "lens
    /// area" is taken as 1, as in pbrt-v4).
    pub pdf: f32,
    /// Raster position the reference point projects to.
    pub raster: Vec2,
    /// The camera position (pinhole).
    pub p: Vec3,
}

impl Camera {
    /// Unit viewing direction (camera −Z in world space).
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Area of the image rectangle on the plane at distance 1 in front of a perspective
    /// camera (None for orthographic cameras).
    fn image_area_at_unit_distance(&self) -> Option<f32> {
        match self.projection {
            Projection::Perspective { .. } => {
                let th = self.tan_half_yfov;
                let aspect = self.width as f32 / self.height as f32;
                Some(4.0 * th * th * aspect)
            }
            Projection::Orthographic { .. } => None,
        }
    }

    /// Importance `We` emitted by a pinhole perspective camera along the world direction
    /// `d` (unit, leaving the camera), and the raster position it hits (pbrt-v4
    /// `PerspectiveCamera::We`): `We = 1 / (A cos⁴θ)` inside the image, 0 outside, where
    /// `A` is the image area at distance 1 and θ the angle to the viewing axis.
    ///
    /// Normalisation: ∫ We cos θ dω = 1 over the whole image, so a light-tracing estimate
    /// `β·f·We·cosθ/…` measures the **image average**; adding each light path's
    /// contribution to the pixel it lands in and dividing the sums by the number of light
    /// paths per pixel (the samples per pixel) gives pixel values with the box filter of
    /// [`crate::film::Film`] (pbrt's splat scale 1/spp).
    ///
    /// Orthographic cameras have a delta direction distribution: `None` (light tracing to
    /// them, the t = 1 strategies of bidirectional methods, is impossible).
    pub fn we(&self, d: Vec3) -> Option<(f32, Vec2)> {
        let a = self.image_area_at_unit_distance()?;
        let cos = d.dot(self.forward());
        if cos <= 0.0 {
            return None;
        }
        let raster = self.project(self.position() + d)?;
        let c2 = cos * cos;
        Some((1.0 / (a * c2 * c2), raster))
    }

    /// Densities (position, direction) with which [`Camera::generate_ray`] with a raster
    /// position uniform over the whole image produces a ray along the world direction `d`
    /// (pbrt-v4 `PDF_We`): position 1 (pinhole, a delta), direction `1/(A cos³θ)` w.r.t.
    /// solid angle; (0, 0) outside the image. Orthographic: `(1/A_film, 1)` — a delta
    /// direction; callers treat the camera vertex as degenerate.
    pub fn pdf_we(&self, d: Vec3) -> (f32, f32) {
        match self.image_area_at_unit_distance() {
            Some(a) => {
                let cos = d.dot(self.forward());
                if cos <= 0.0 || self.project(self.position() + d).is_none() {
                    return (0.0, 0.0);
                }
                (1.0, 1.0 / (a * cos * cos * cos))
            }
            None => {
                let Projection::Orthographic { ymag, .. } = self.projection else {
                    unreachable!()
                };
                let aspect = self.width as f32 / self.height as f32;
                (1.0 / (4.0 * ymag * ymag * aspect), 1.0)
            }
        }
    }

    /// Connects a world point `p` to the pinhole (pbrt-v4 `PerspectiveCamera::SampleWi`;
    /// uses no random numbers). `None` when `p` is behind the camera, outside the image, or
    /// the camera is orthographic (see [`Camera::we`]).
    pub fn sample_wi(&self, p: Vec3) -> Option<CameraWiSample> {
        let cam = self.position();
        let to_cam = cam - p;
        let d2 = to_cam.length_squared();
        if d2 == 0.0 || !d2.is_finite() {
            return None;
        }
        let dist = d2.sqrt();
        let wi = to_cam / dist;
        let (we, raster) = self.we(-wi)?;
        let cos = (-wi).dot(self.forward());
        Some(CameraWiSample {
            wi,
            we,
            pdf: d2 / cos,
            raster,
            p: cam,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_generate_ray() {
        let m = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_y(0.3),
            Vec3::new(1.0, 2.0, 3.0),
        );
        for proj in [
            Projection::Perspective {
                yfov: 0.7,
                aspect: None,
                znear: 0.1,
            },
            Projection::Orthographic {
                xmag: 2.0,
                ymag: 1.5,
            },
        ] {
            let cam = Camera::new(m, proj, 320, 200);
            for raster in [
                Vec2::new(10.5, 20.25),
                Vec2::new(300.0, 150.0),
                Vec2::new(160.0, 100.0),
            ] {
                let ray = cam.generate_ray(raster);
                let back = cam.project(ray.at(5.0)).unwrap();
                assert!((back - raster).length() < 1e-2, "{back} vs {raster}");
            }
        }
    }

    /// ∫ We cos θ dω over the sphere is 1 (importance normalised over the image), and the
    /// pdf of directions is We·cos θ (pbrt-v4's pinhole camera).
    #[test]
    fn importance_integrates_to_one_over_the_image() {
        let cam = Camera::new(
            Affine3A::from_rotation_translation(glam::Quat::from_rotation_x(0.2), Vec3::ONE),
            Projection::Perspective {
                yfov: 0.9,
                aspect: None,
                znear: 0.1,
            },
            64,
            48,
        );
        let mut r = crate::sampling::rng::Pcg32::new(3, 4);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let d = crate::sampling::warps::sample_uniform_sphere(Vec2::new(
                r.next_f32(),
                r.next_f32(),
            ));
            if let Some((we, raster)) = cam.we(d) {
                let cos = d.dot(cam.forward());
                let (_, pdf) = cam.pdf_we(d);
                assert!((pdf - we * cos).abs() <= 1e-4 * pdf);
                let back = cam.generate_ray(raster).d;
                assert!((back - d).length() < 1e-3);
                sum += (we * cos) as f64 / crate::sampling::warps::UNIFORM_SPHERE_PDF as f64;
            }
        }
        let m = sum / n as f64;
        // The image covers ~0.3 of the sphere's directions: relative standard error of the
        // mean ≈ 1.5/sqrt(n·0.3) < 0.7%; 3% leaves a wide margin.
        assert!((m - 1.0).abs() < 0.03, "∫We cos = {m}");
        let s = cam.sample_wi(Vec3::new(1.2, 0.9, -3.0)).unwrap();
        assert!((cam.project(Vec3::new(1.2, 0.9, -3.0)).unwrap() - s.raster).length() < 1e-3);
    }
}
