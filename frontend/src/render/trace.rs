//! Whitted-style ray tracing under an [`EffectPlan`].
//!
//! `L = ka·Ia + Σ_lights [kd·E·max(0, n·l) + ks·E·max(0, n·h)^p] + kr·L(reflected) + kt·L(refracted)`
//! with `E = I/r²` for point lights and `E = I` for directional ones, `n` the normal facing the
//! incoming ray, `h = normalize(l + v)`. A light contributes nothing where `n·l ≤ 0` (the
//! surface faces away from it) or where a shadow ray finds an occluder (lights with
//! `cast_shadows`). Shadow rays are any-hit queries started with the core's robust spawn
//! ([`spawn_ray_to`] / [`spawn_ray`]), never with a scene epsilon.

use super::geom::{QueryCtx, SurfaceHit};
use super::plan::EffectPlan;
use crate::scene::{LightKind, Scene};
use glam::Vec3;
use halfray_core::{Ray, spawn_ray, spawn_ray_to};

/// Rays cast, per kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Shadow (occlusion) rays.
    pub shadow: u64,
    /// Mirror reflection rays (including total internal reflection).
    pub reflection: u64,
    /// Refraction rays.
    pub refraction: u64,
}

impl RayCounts {
    /// Sum of all kinds.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflection + self.refraction
    }

    /// Adds `o`.
    pub fn add(&mut self, o: &Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflection += o.reflection;
        self.refraction += o.refraction;
    }
}

/// Mirror direction `r = d − 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell refraction of unit `d` through a surface with unit normal `n` facing against `d`,
/// with `eta = n_incident / n_transmitted`; `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (eta * d + (eta * cos_i - k.sqrt()) * n).normalize())
}

/// The tracer: scene + plan.
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The plan.
    pub plan: &'a EffectPlan,
}

impl Tracer<'_> {
    /// A fresh query context (counters zero).
    pub fn ctx(&self) -> QueryCtx {
        QueryCtx {
            force_intervals: self.plan.intervals_everywhere,
            ..QueryCtx::default()
        }
    }

    /// Closest hit over every object.
    pub fn closest(&self, ray: &Ray, ctx: &mut QueryCtx) -> Option<SurfaceHit> {
        let mut r = *ray;
        let mut best = None;
        for o in &self.scene.objects {
            if let Some(h) = o.closest(&r, ctx) {
                r.t_max = h.hit.t;
                best = Some(h);
            }
        }
        best
    }

    /// Whether anything blocks `ray` in its interval.
    pub fn occluded(&self, ray: &Ray, ctx: &mut QueryCtx) -> bool {
        self.scene.objects.iter().any(|o| o.occludes(ray, ctx))
    }

    /// Radiance along a ray (already counted by the caller) at recursion `depth`.
    pub fn radiance(&self, ray: &Ray, depth: u32, ctx: &mut QueryCtx, n: &mut RayCounts) -> Vec3 {
        match self.closest(ray, ctx) {
            Some(h) => self.shade(ray, &h, depth, ctx, n),
            None => self.scene.background,
        }
    }

    /// Local illumination plus the recursive terms at a hit.
    pub fn shade(
        &self,
        ray: &Ray,
        sh: &SurfaceHit,
        depth: u32,
        ctx: &mut QueryCtx,
        n: &mut RayCounts,
    ) -> Vec3 {
        let scene = self.scene;
        let mi = sh.material as usize;
        let m = &scene.materials[mi];
        let hit = &sh.hit;
        let d = ray.direction.normalize();
        let v = -d;
        let nrm = hit.facing_normal();
        let mut color = m.ambient * scene.ambient;
        let specular = self.plan.specular[mi];
        for (li, light) in scene.lights.iter().enumerate() {
            let (l, e, shadow_ray) = match light.kind {
                LightKind::Point { position } => {
                    let to = position - hit.point;
                    let r2 = to.length_squared();
                    (
                        to.normalize_or_zero(),
                        light.intensity / r2,
                        spawn_ray_to(hit, position),
                    )
                }
                LightKind::Directional { direction } => {
                    (-direction, light.intensity, spawn_ray(hit, -direction))
                }
            };
            let ndotl = nrm.dot(l);
            let cast = self.plan.shadow_rays[li] && (ndotl > 0.0 || self.plan.forced);
            let mut blocked = false;
            if cast {
                n.shadow += 1;
                blocked = self.occluded(&shadow_ray, ctx) && light.cast_shadows;
            }
            if !(ndotl > 0.0) || blocked || !e.is_finite() {
                continue;
            }
            color += m.diffuse * e * ndotl;
            if specular {
                let h = (l + v).normalize_or_zero();
                color += m.specular * e * nrm.dot(h).max(0.0).powf(m.shininess);
            }
        }
        if depth >= self.plan.max_depth {
            return color;
        }
        if self.plan.reflect[mi] && (m.mirror > 0.0 || self.plan.forced) {
            let r = reflect(d, nrm);
            n.reflection += 1;
            color += m.mirror * self.radiance(&spawn_ray(hit, r), depth + 1, ctx, n);
        }
        if self.plan.refract[mi] && (m.transparency > 0.0 || self.plan.forced) {
            let eta = if hit.front_face { 1.0 / m.ior } else { m.ior };
            let t = match refract(d, nrm, eta) {
                Some(t) => {
                    n.refraction += 1;
                    t
                }
                None => {
                    // Total internal reflection: the transmitted share is reflected.
                    n.reflection += 1;
                    reflect(d, nrm)
                }
            };
            color += m.transparency * self.radiance(&spawn_ray(hit, t), depth + 1, ctx, n);
        }
        color
    }
}
