//! Analytic checks of the renderer: shading against the closed-form formulas, shadows, mirror
//! reflection, Snell refraction through a slab, and transformed normals.

use glam::{Vec3, Vec4};
use halfray::render::plan::EffectPlan;
use halfray::render::trace::{RayCounts, Tracer, refract};
use halfray::render::{Mode, RenderOptions, render};
use halfray_core::{Ray, spawn_ray};

mod common;
use common::{material, parse_scene, plane, point_light, sphere};

/// How far past the half-step of rounding to 8 bits an encoded byte may sit from the exact
/// encoding of its linear value (in units of one 8-bit step): the renderer encodes in `f32`
/// (`powf` and the products round, a few ulps of the value, about `10⁻⁴` of a step), the test's
/// formula in `f64`.
const EIGHT_BIT_SLACK: f64 = 1.0e-3;

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol * (1.0 + b.abs().max_element())
}

const ORTHO: &str = r#"
[camera]
type = "orthographic"
eye = [0, 0, 5]
look_at = [0, 0, 0]
view_size = 2.5
width = 41
height = 41
"#;

#[test]
fn lit_sphere_pixel_equals_lambert_plus_blinn_phong() {
    let light = point_light("[3, 4, 6]", "30");
    let sphere = sphere("[0, 0, 0]", "1", "m");
    let text = format!(
        r#"ambient = [0.1, 0.2, 0.3]
{ORTHO}
{light}color = [1.0, 0.9, 0.8]

[material.m]
ambient = [0.5, 0.5, 0.5]
diffuse = [0.7, 0.3, 0.2]
specular = [0.4, 0.4, 0.4]
shininess = 25

{sphere}"#
    );
    let s = parse_scene(&text);
    let out = render(&s, &RenderOptions::default());
    let mut checked = 0;
    for (i, j) in [(20, 20), (25, 14), (12, 27), (28, 22), (20, 5)] {
        let ray = s.camera.pixel_ray(i, j);
        let (x, y) = (ray.origin.x, ray.origin.y);
        let z2 = 1.0 - x * x - y * y;
        assert!(z2 > 0.0, "pixel ({i}, {j}) misses the sphere");
        let p = Vec3::new(x, y, z2.sqrt());
        let n = p;
        let light = Vec3::new(3.0, 4.0, 6.0);
        let intensity = Vec3::new(1.0, 0.9, 0.8) * 30.0;
        let to = light - p;
        let e = intensity / to.length_squared();
        let l = to.normalize();
        let v = Vec3::Z;
        let h = (l + v).normalize();
        let expected = Vec3::splat(0.5) * Vec3::new(0.1, 0.2, 0.3)
            + Vec3::new(0.7, 0.3, 0.2) * e * n.dot(l).max(0.0)
            + Vec3::splat(0.4) * e * n.dot(h).max(0.0).powf(25.0);
        let got = out.pixel(i, j);
        assert_eq!(got.w, 1.0);
        assert!(
            close(got.truncate(), expected, 1e-4),
            "pixel ({i}, {j}): got {got:?}, expected {expected:?}"
        );
        checked += 1;
    }
    assert_eq!(checked, 5);
    // Corners miss: alpha 0.
    assert_eq!(out.pixel(0, 0).w, 0.0);
    // And the PNG bytes are the sRGB encoding of the same value: IEC 61966-2-1's transfer
    // function, written out here in `f64`, then 8 bits rounded to nearest.
    let rgba = out.to_rgba8(Mode::Color, Default::default());
    let k = (20 * 41 + 20) * 4;
    let want = out.pixel(20, 20);
    let srgb = |v: f64| {
        let v = v.clamp(0.0, 1.0);
        if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
    };
    for c in 0..3 {
        let exact = 255.0 * srgb(f64::from(want[c]));
        assert!(
            (f64::from(rgba[k + c]) - exact).abs() <= 0.5 + EIGHT_BIT_SLACK,
            "channel {c}: byte {} for {exact}",
            rgba[k + c]
        );
    }
    assert_eq!(rgba[k + 3], 255);
}

#[test]
fn point_in_shadow_gets_ambient_only() {
    let light = point_light("[0, 0, 4]", "20");
    let floor = plane("[0, 0, 0]", "[0, 0, 1]", "floor");
    let blocker = sphere("[0, 0, 2]", "0.05", "blocker");
    let text = format!(
        r#"ambient = [0.2, 0.2, 0.2]
{ORTHO}
{light}
[material.floor]
ambient = [0.6, 0.5, 0.4]
diffuse = [0.9, 0.9, 0.9]
specular = [0.5, 0.5, 0.5]

[material.blocker]
diffuse = [0.1, 0.1, 0.1]

{floor}
# A small sphere between the light and the floor's centre, seen edge-on by no pixel we test.
{blocker}"#
    );
    let s = parse_scene(&text);
    let plan = EffectPlan::derive(&s, false);
    let tracer = Tracer {
        scene: &s,
        plan: &plan,
    };
    // A ray hitting the floor right under the blocker, from the side (so it misses the blocker).
    let ray = Ray::new(Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0));
    let mut ctx = tracer.ctx();
    let mut n = RayCounts::default();
    let hit = tracer.closest(&ray, &mut ctx).expect("floor");
    assert!(hit.hit.point.length() < 1e-6, "{:?}", hit.hit.point);
    let c = tracer.shade(&ray, &hit, 0, &mut ctx, &mut n);
    assert_eq!(c, Vec3::new(0.6, 0.5, 0.4) * 0.2, "ambient only");
    assert_eq!(n.shadow, 1);
    // A lit floor point nearby is brighter than ambient.
    let ray = Ray::new(Vec3::new(0.5, 0.5, 1.0), Vec3::new(0.0, 0.0, -1.0));
    let hit = tracer.closest(&ray, &mut ctx).unwrap();
    let lit = tracer.shade(&ray, &hit, 0, &mut ctx, &mut n);
    assert!(lit.x > 0.6 * 0.2 + 0.1, "{lit:?}");
}

#[test]
fn mirror_facing_coloured_plane_returns_colour_times_reflectance() {
    let mirror = plane("[0, 0, 0]", "[0, 0, 1]", "mirror");
    let paint = plane("[0, 0, 10]", "[0, 0, -1]", "paint");
    let black = "[0, 0, 0]";
    let silver = material(
        "mirror",
        &[("ambient", black), ("diffuse", black), ("mirror", "0.6")],
    );
    let colour = material(
        "paint",
        &[("ambient", "[0.2, 0.7, 0.4]"), ("diffuse", black)],
    );
    let text = format!(
        r#"ambient = [1, 1, 1]
{ORTHO}
{silver}
{colour}
{mirror}
# Behind the camera, facing the mirror.
{paint}"#
    );
    let s = parse_scene(&text);
    let out = render(&s, &RenderOptions::default());
    let want = Vec3::new(0.2, 0.7, 0.4) * 0.6;
    for p in &out.pixels {
        assert!(close(p.truncate(), want, 1e-6), "{p:?} vs {want:?}");
        assert_eq!(p.w, 1.0);
    }
    assert_eq!(out.counts.reflection, 41 * 41);
    assert_eq!(out.counts.shadow, 0);
}

#[test]
fn refracting_slab_shifts_a_ray_as_snell_predicts() {
    let ior = 1.5f32;
    let text = format!(
        r#"{ORTHO}
[material.glass]
transparency = 1.0
ior = {ior}

[[object]]
type = "box"
min = [-100, -100, -1]
max = [100, 100, 0]
material = "glass"
"#
    );
    let s = parse_scene(&text);
    let plan = EffectPlan::derive(&s, false);
    let tracer = Tracer {
        scene: &s,
        plan: &plan,
    };
    let mut ctx = tracer.ctx();
    for deg in [0.0f32, 10.0, 30.0, 60.0] {
        let th = deg.to_radians();
        let d = Vec3::new(th.sin(), 0.0, -th.cos());
        let ray = Ray::new(-d / d.z.abs(), d);
        let h1 = tracer.closest(&ray, &mut ctx).unwrap();
        assert!(h1.hit.front_face);
        let t1 = refract(d, h1.hit.facing_normal(), 1.0 / ior).unwrap();
        // Snell: sin θt = sin θi / n.
        let sin_t = th.sin() / ior;
        assert!((t1.x - sin_t).abs() < 1e-6, "{deg}°: {t1:?}");
        let inner = spawn_ray(&h1.hit, t1);
        let h2 = tracer.closest(&inner, &mut ctx).unwrap();
        assert!(!h2.hit.front_face, "leaves the slab");
        // Lateral position on the far face: x = tan θt · thickness.
        let tan_t = sin_t / (1.0 - sin_t * sin_t).sqrt();
        assert!((h2.hit.point.z + 1.0).abs() < 1e-6);
        assert!(
            (h2.hit.point.x - tan_t).abs() < 1e-5,
            "{deg}°: exit x {} vs {tan_t}",
            h2.hit.point.x
        );
        // Leaving: parallel to the incoming ray, displaced sideways by
        // t·sin(θi − θt)/cos θt (t = 1).
        let out = refract(t1, h2.hit.facing_normal(), ior).unwrap();
        assert!((out - d).length() < 1e-5, "{deg}°: {out:?} vs {d:?}");
        let straight_x = th.tan();
        let shift = (straight_x - h2.hit.point.x) * th.cos();
        let th_t = sin_t.asin();
        let predicted = (th - th_t).sin() / th_t.cos();
        assert!(
            (shift - predicted).abs() < 1e-5,
            "{deg}°: {shift} vs {predicted}"
        );
    }
    // Total internal reflection from inside at a grazing angle.
    assert!(refract(Vec3::new(0.9, 0.0, -0.435_889_9), Vec3::Z, ior).is_none());
}

#[test]
fn scaled_sphere_normal_is_the_analytic_ellipsoid_normal() {
    let sphere = sphere("[0, 0, 0]", "1", "m");
    let text = format!(
        r#"{ORTHO}
[material.m]
diffuse = [1, 1, 1]

{sphere}transform = [{{ scale = [1.0, 0.5, 0.8] }}, {{ rotate = {{ axis = [0, 0, 1], degrees = 0 }} }}]
"#
    );
    let s = parse_scene(&text);
    let plan = EffectPlan::derive(&s, false);
    let tracer = Tracer {
        scene: &s,
        plan: &plan,
    };
    let (a, b, c) = (1.0f32, 0.5f32, 0.8f32);
    let mut ctx = tracer.ctx();
    for (x, y) in [(0.0, 0.0), (0.5, 0.2), (-0.7, 0.3), (0.3, -0.4), (0.9, 0.1)] {
        let ray = Ray::new(Vec3::new(x, y, 5.0), Vec3::new(0.0, 0.0, -1.0));
        let h = tracer.closest(&ray, &mut ctx).unwrap().hit;
        let p = h.point;
        let z = c * (1.0 - (x / a).powi(2) - (y / b).powi(2)).sqrt();
        assert!((p - Vec3::new(x, y, z)).length() < 1e-5, "{p:?}");
        let analytic = Vec3::new(p.x / (a * a), p.y / (b * b), p.z / (c * c)).normalize();
        assert!(
            (h.normal - analytic).length() < 1e-5,
            "({x}, {y}): {:?} vs {analytic:?}",
            h.normal
        );
    }
    // The normal debug mode shows the same normal, encoded n·½ + ½.
    let out = render(
        &s,
        &RenderOptions {
            mode: Mode::Normal,
            ..RenderOptions::default()
        },
    );
    let ray = s.camera.pixel_ray(27, 17);
    let h = tracer.closest(&ray, &mut ctx).unwrap().hit;
    let want = (h.normal * 0.5 + 0.5).extend(1.0);
    assert!((out.pixel(27, 17) - want).length() < 1e-6);
    assert_eq!(out.pixel(0, 0), Vec4::ZERO);
}

/// The perspective camera against the pinhole model derived independently: frame
/// `forward = (look_at − eye)/|…|`, `right = forward × y/|…|`, `up = right × forward` (the
/// scene format's world up is `+y`), vertical field of view `fov`, image `y` pointing down. A
/// world point `P` with camera coordinates `(r, u, f)` then appears at pixel
/// `x = w/2·(1 + r/(f·tan(fov/2)·w/h))`, `y = h/2·(1 − u/(f·tan(fov/2)))`. Small spheres at
/// such points are rendered (radius `0.025·f`: about 1.6 pixels): the pixel under each
/// predicted position shows the sphere, and the pixels 5 away in every direction show the
/// background.
#[test]
fn spheres_appear_where_the_pinhole_model_projects_them() {
    let (w, h, fov) = (64u32, 48u32, 40.0f64);
    let eye = glam::DVec3::new(1.0, 2.0, 3.0);
    let look = glam::DVec3::new(-2.0, 0.5, -1.0);
    let forward = (look - eye).normalize();
    let right = forward.cross(glam::DVec3::Y).normalize();
    let up = right.cross(forward);
    let tan = (fov.to_radians() / 2.0).tan();
    let aspect = f64::from(w) / f64::from(h);
    let project = |p: glam::DVec3| {
        let q = p - eye;
        let (r, u, f) = (q.dot(right), q.dot(up), q.dot(forward));
        (
            f64::from(w) / 2.0 * (1.0 + r / (f * tan * aspect)),
            f64::from(h) / 2.0 * (1.0 - u / (f * tan)),
        )
    };
    // Points across the view at depths 3–7, each kept 6 pixels inside the image.
    let points: Vec<glam::DVec3> = [
        (0.1, 0.05, 5.0),
        (1.2, 0.6, 4.0),
        (-1.5, -0.7, 6.0),
        (0.6, -0.5, 3.0),
        (-1.0, 1.1, 7.0),
    ]
    .iter()
    .map(|&(a, b, d)| eye + forward * d + right * a + up * b)
    .collect();
    let spheres: String = points
        .iter()
        .map(|p| {
            let radius = 0.025 * (*p - eye).dot(forward);
            sphere(
                &format!("[{}, {}, {}]", p.x, p.y, p.z),
                &radius.to_string(),
                "red",
            )
        })
        .collect();
    let text = format!(
        "ambient = [1, 1, 1]\n[camera]\neye = [1, 2, 3]\nlook_at = [-2, 0.5, -1]\nfov = {fov}\n\
         width = {w}\nheight = {h}\n\n[material.red]\nambient = [1, 0, 0]\ndiffuse = [0, 0, 0]\n\n{spheres}"
    );
    let out = render(&parse_scene(&text), &RenderOptions::default());
    for p in &points {
        let (x, y) = project(*p);
        assert!(
            (6.0..f64::from(w) - 6.0).contains(&x) && (6.0..f64::from(h) - 6.0).contains(&y),
            "{p} projects to ({x}, {y}), too near the border for this test"
        );
        let (i, j) = (x as u32, y as u32);
        assert!(
            out.pixel(i, j).x > 0.5,
            "{p}: predicted at ({x:.2}, {y:.2}), pixel ({i}, {j}) = {:?}",
            out.pixel(i, j)
        );
        for (di, dj) in [(5, 0), (-5, 0), (0, 5), (0, -5)] {
            let (a, b) = ((i as i32 + di) as u32, (j as i32 + dj) as u32);
            assert_eq!(
                out.pixel(a, b),
                Vec4::ZERO,
                "{p}: pixel ({a}, {b}) not background"
            );
        }
    }
}

/// No shadow acne on transformed objects: a convex mesh (the octahedron) and a
/// sphere, each under a non-uniform scale, a rotation and a translation far from the origin,
/// alone in the scene under one point light. Nothing can shadow a convex object's own
/// surface where it faces the light, so every pixel whose surface faces both the camera and
/// the light (`n·l > 0.05`) must be lit: brighter than its ambient term. A shadow ray that
/// re-hit its own surface (spawned inside it by the transform's rounding) would leave it at
/// the ambient term.
#[test]
fn transformed_convex_objects_do_not_shadow_themselves() {
    let meshes = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/meshes");
    let transform = "transform = [{ scale = [1.0, 2.5, 0.7] }, { rotate = { axis = [1, 1, 0], \
                     degrees = 37 } }, { translate = [300.5, -120.25, 77.75] }]";
    let objects = [
        format!(
            "[mesh.oct]\nfile = \"{meshes}/octahedron.obj\"\n\n[[object]]\ntype = \"mesh\"\n\
             mesh = \"oct\"\nmaterial = \"m\"\n{transform}\n"
        ),
        format!(
            "[[object]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n\
             {transform}\n"
        ),
    ];
    for object in objects {
        let text = format!(
            "ambient = [0.1, 0.1, 0.1]\n[camera]\neye = [306, -117, 84]\nlook_at = [300.5, -120.25, \
             77.75]\nfov = 40\nwidth = 64\nheight = 64\n\n[[light]]\ntype = \"point\"\nposition = \
             [304, -112, 86]\nintensity = 100\n\n[material.m]\nambient = [1, 1, 1]\n\
             diffuse = [0.8, 0.8, 0.8]\nspecular = [0, 0, 0]\n\n{object}"
        );
        let s = parse_scene(&text);
        let plan = EffectPlan::derive(&s, false);
        assert!(plan.shadow_rays[0]);
        let tracer = Tracer {
            scene: &s,
            plan: &plan,
        };
        let mut ctx = tracer.ctx();
        let light = Vec3::new(304.0, -112.0, 86.0);
        let mut lit_points = 0;
        for j in 0..64 {
            for i in 0..64 {
                let ray = s.camera.pixel_ray(i, j);
                let Some(hit) = tracer.closest(&ray, &mut ctx) else {
                    continue;
                };
                let n = hit.hit.normal;
                let l = (light - hit.hit.point).normalize();
                if n.dot(-ray.direction) <= 0.0 || n.dot(l) <= 0.05 {
                    continue;
                }
                let mut counts = RayCounts::default();
                let c = tracer.shade(&ray, &hit, 0, &mut ctx, &mut counts);
                assert_eq!(counts.shadow, 1);
                assert!(
                    c.x > 0.1 + 1e-3,
                    "pixel ({i}, {j}) facing the light (n·l = {}) is in shadow: {c:?}\n{object}",
                    n.dot(l)
                );
                lit_points += 1;
            }
        }
        assert!(lit_points > 200, "{lit_points} lit points tested\n{object}");
    }
}
