//! Cameras: perspective (glTF yfov) and orthographic, looking down their local −Z.

use crate::geometry::Ray;
use crate::math::{Affine3A, Vec2, Vec3};
use crate::scene::desc::Projection;

#[derive(Clone, Debug)]
pub struct Camera {
    /// Rigid `world_from_camera` (scale removed).
    pub world_from_camera: Affine3A,
    pub projection: Projection,
    pub width: u32,
    pub height: u32,
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
        Camera {
            world_from_camera: Affine3A::from_rotation_translation(rot, trans),
            projection,
            width,
            height,
        }
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
            Projection::Perspective { yfov, .. } => {
                let th = (0.5 * yfov).tan();
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
        let c = self.world_from_camera.inverse().transform_point3(p);
        let (w, h) = (self.width as f32, self.height as f32);
        let aspect = w / h;
        let ndc = match self.projection {
            Projection::Perspective { yfov, .. } => {
                if c.z >= 0.0 {
                    return None;
                }
                let th = (0.5 * yfov).tan();
                Vec2::new(c.x / (-c.z * th * aspect), c.y / (-c.z * th))
            }
            Projection::Orthographic { ymag, .. } => Vec2::new(c.x / (ymag * aspect), c.y / ymag),
        };
        let r = Vec2::new((ndc.x + 1.0) * 0.5 * w, (1.0 - ndc.y) * 0.5 * h);
        (r.x >= 0.0 && r.y >= 0.0 && r.x < w && r.y < h).then_some(r)
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
}
