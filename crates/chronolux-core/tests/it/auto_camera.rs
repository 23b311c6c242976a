//! The automatic camera of a file without one turns towards the side the light comes from.

use chronolux_core::color::Rgb;
use chronolux_core::geometry::Bounds3;
use chronolux_core::light::{Environment, Light};
use chronolux_core::math::Vec3;
use chronolux_core::scene::desc::default_environment;
use chronolux_core::scene::frame::{auto_camera, light_side};

/// A few unit cubes on the ground around the origin: bounds [−3, 3] × [0, 1] × [−3, 3].
fn cubes() -> Bounds3 {
    Bounds3 {
        min: Vec3::new(-3.0, 0.0, -3.0),
        max: Vec3::new(3.0, 1.0, 3.0),
    }
}

fn eye_and_forward(lights: &[Light]) -> (Vec3, Vec3) {
    let b = cubes();
    let (_, r) = b.bounding_sphere();
    let cam = auto_camera(b, light_side(lights, b, r), 64, 64);
    (cam.position(), cam.forward())
}

#[test]
fn without_directional_light_the_camera_stays_in_front() {
    // A uniform environment lights every side alike: the camera of old, on +Z slightly
    // above (elevation atan(0.25) ≈ 14°).
    let (eye, fwd) = eye_and_forward(&[Light::Environment {
        env: Environment::uniform(Rgb::ONE),
    }]);
    let c = cubes().center();
    let v = (eye - c).normalize();
    assert!(
        (v - Vec3::new(0.0, 0.25, 1.0).normalize()).length() < 1e-5,
        "{v}"
    );
    assert!(fwd.dot(c - eye) > 0.0);
}

#[test]
fn a_point_light_above_and_behind_is_seen_from_its_side() {
    // One point light above the cubes, behind them (−Z): the old camera (+Z, 14° up) saw
    // only the faces turned away from it.
    let light = Vec3::new(0.0, 6.0, -4.0);
    let (eye, fwd) = eye_and_forward(&[Light::Point {
        p: light,
        intensity: Rgb::splat(100.0),
    }]);
    let c = cubes().center();
    // Looking down at the tops, which the light faces: (0, 0.24, 0.97) + the unit direction
    // to the light (0, 0.78, −0.62) rises above 60°, so the elevation is held at 60° (sin
    // 0.866), on +Z where the sum still points. The old view made −0.37 of cosine with the
    // light's direction, this one 0.41.
    assert!(fwd.y < -0.85, "forward {fwd}");
    let v = (eye - c).normalize();
    assert!((v.y - 60f32.to_radians().sin()).abs() < 1e-4, "{v}");
    assert!(v.dot((light - c).normalize()) > 0.4, "{v}");
}

#[test]
fn the_default_environment_is_seen_from_above() {
    // The fallback light (sky above, ground below) lights the tops: the camera rises to
    // about 43° (view direction (0, 0.24, 0.97) + (0, 2/3, 0)), still in front.
    let (eye, _) = eye_and_forward(&[Light::Environment {
        env: default_environment(),
    }]);
    let v = (eye - cubes().center()).normalize();
    let elevation = v.y.asin().to_degrees();
    assert!(
        v.z > 0.0 && (elevation - 43.1).abs() < 1.0,
        "{v}, {elevation}°"
    );
}
