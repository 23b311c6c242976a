//! The one next-event-estimation kernel (direct light by light sampling with a
//! ray-traced shadow) and the emitted radiance of a sampled light point, shared by the
//! path tracer ([`crate::kernels::path`]), the eye pass of the photon methods ([`crate::kernels::elements::view`])
//! and, for the emission helpers, BDPT and the photon kernel.
//!
//! ## Sample dimensions
//! [`next_event`] takes its three uniforms (`u_light`, `u_lp`) from the caller, which
//! draws them whether or not the surface has a non-delta lobe, so every bounce's
//! dimensions stay aligned across samples.

use chronolux_core::bsdf::{Bsdf, TransportMode};
use chronolux_core::color::Rgb;
use chronolux_core::geometry::spawn_ray_to;
use chronolux_core::light::Light;
use chronolux_core::material;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::power_heuristic;
use chronolux_core::scene::frame::{FrameScene, SurfaceInteraction};
use chronolux_core::stats::Stats;

/// Emitted radiance of `light` at the point with barycentrics `bary` on it (as returned by
/// [`Light::sample_li`]): the textured emission of triangle lights, `le` (the light's own
/// value) for every other light or an untextured triangle.
pub fn light_radiance(scene: &FrameScene, light: &Light, le: Rgb, bary: Vec2) -> Rgb {
    if let Light::Triangle { tri, instance, .. } = light {
        let g = &scene.geometry[tri.geometry as usize];
        let m = &scene.materials[g.material as usize];
        if m.emissive_texture.is_some() {
            let si = scene.surface_at(*tri, *instance, bary.x, bary.y, None);
            return material::emission_at(m, &scene.textures, &si.shading);
        }
    }
    le
}

/// Emitted radiance of `light` at a world point `p` on it: as [`light_radiance`], with the
/// barycentrics of `p` on a triangle light recovered by least squares on its edges
/// (clamped into the triangle). For emission samples ([`Light::sample_le`]) that report a
/// point but no barycentrics.
pub fn light_radiance_at(scene: &FrameScene, light: &Light, le: Rgb, p: Vec3) -> Rgb {
    let Light::Triangle {
        p0, e1, e2, tri, ..
    } = light
    else {
        return le;
    };
    let g = &scene.geometry[tri.geometry as usize];
    if scene.materials[g.material as usize]
        .emissive_texture
        .is_none()
    {
        return le;
    }
    let d = p - *p0;
    let (a, b, c) = (e1.dot(*e1), e1.dot(*e2), e2.dot(*e2));
    let (r1, r2) = (d.dot(*e1), d.dot(*e2));
    let det = a * c - b * b;
    if det <= 0.0 {
        return le;
    }
    let b1 = ((c * r1 - b * r2) / det).clamp(0.0, 1.0);
    let b2 = ((a * r2 - b * r1) / det).clamp(0.0, 1.0 - b1);
    light_radiance(scene, light, le, Vec2::new(b1, b2))
}

/// How [`next_event`] weights its light sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NeeWeight {
    /// Power-heuristic MIS against BSDF sampling (the caller also picks up emission hit by
    /// BSDF-sampled rays, weighted the other way).
    Mis,
    /// Weight 1: the caller never counts emission reached after a non-delta bounce.
    LightOnly,
}

/// Power-heuristic MIS weight of emission from light `li` at `to` (for a light at
/// infinity, any point along the direction from `from`) found by a BSDF-sampled ray from
/// `from` with solid-angle pdf `bsdf_pdf`, against [`next_event`]'s light sampling.
#[inline]
pub fn bsdf_hit_weight(scene: &FrameScene, li: usize, from: Vec3, to: Vec3, bsdf_pdf: f32) -> f32 {
    let pl = scene.light_sampler.pmf(li) * scene.lights[li].pdf_li(from, to);
    power_heuristic(1.0, bsdf_pdf, 1.0, pl)
}

/// Next-event estimation at `si` seen from `wo`: one light chosen by the scene's light
/// sampler with `u_light`, one point on it with `u_lp`, a shadow ray, through the
/// non-delta lobes of `bsdf`. Returns `beta · f · cos · Le · w / (pmf · pdf)` (zero when
/// nothing is sampled, the BSDF is zero there or the light is occluded); counts its shadow
/// ray in `stats`. The caller checks [`Bsdf::has_non_delta`] first.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn next_event(
    scene: &FrameScene,
    si: &SurfaceInteraction,
    wo: Vec3,
    bsdf: &Bsdf,
    beta: Rgb,
    u_light: f32,
    u_lp: Vec2,
    weight: NeeWeight,
    stats: &mut Stats,
) -> Rgb {
    let Some((li_idx, pmf, _)) = scene.light_sampler.sample(u_light) else {
        return Rgb::ZERO;
    };
    let light = &scene.lights[li_idx];
    let Some(ls) = light.sample_li(si.p, u_lp, scene.scene_radius) else {
        return Rgb::ZERO;
    };
    if !(pmf > 0.0 && ls.pdf > 0.0) {
        return Rgb::ZERO;
    }
    // The BSDF's pdf only where the MIS weight needs it, then from the same pass as f.
    let mis = !(ls.is_delta || weight == NeeWeight::LightOnly);
    let (f, bsdf_pdf) = if mis {
        bsdf.f_pdf(wo, ls.wi, TransportMode::Radiance)
    } else {
        (bsdf.f(wo, ls.wi, TransportMode::Radiance), 0.0)
    };
    let f = f * ls.wi.dot(bsdf.frame.n).abs();
    if f == Rgb::ZERO {
        return Rgb::ZERO;
    }
    stats.shadow_rays += 1;
    if scene.occluded(&spawn_ray_to(si.p, si.ng, ls.p, ls.n)) {
        return Rgb::ZERO;
    }
    let le = light_radiance(scene, light, ls.li, ls.bary);
    let w = if mis {
        power_heuristic(1.0, pmf * ls.pdf, 1.0, bsdf_pdf)
    } else {
        1.0
    };
    beta * f * le * (w / (pmf * ls.pdf))
}
