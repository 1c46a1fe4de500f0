//! The scene's top-level BVH (`scene::top`) against the plain loop over every object it
//! replaced: the same closest object (ties: the object declared last), the same `t`, the same
//! occlusion, on every example scene and on 10 000 spheres with duplicates. Its batch queries
//! (a mesh walking its rays in packets) against the single-ray query, hit for hit, and
//! against the object loop's occlusion, ray for ray; the renderer's batched rows (primary and
//! shadow rays) against single rays, pixel for pixel.

use halfray::render::{Mode, RenderOptions, render};
use halfray::scene::geom::QueryCtx;
use halfray::scene::{Scene, load, parse};
use halfray_core::{Ray, Vec3};
use std::path::Path;

mod common;
use common::{example_scene_paths, lcg, scenes_dir};

/// Every example scene but `bunny.toml` (its 69 451-triangle mesh makes these suites slow),
/// with its path.
fn example_scenes() -> impl Iterator<Item = (std::path::PathBuf, Scene)> {
    let paths = example_scene_paths().into_iter();
    paths.filter(|p| !p.ends_with("bunny.toml")).map(|p| {
        let s = load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        (p, s)
    })
}

/// The reference: every object in declaration order, a later one winning an equal `t`.
fn closest_by_loop(s: &Scene, ray: &Ray, ctx: &mut QueryCtx) -> Option<(u32, f32)> {
    let mut r = *ray;
    let mut best = None;
    for (i, o) in s.objects.iter().enumerate() {
        if let Some(h) = o.closest(&r, ctx) {
            r.t_max = h.hit.t;
            best = Some((i as u32, h.hit.t));
        }
    }
    best
}

fn check(s: &Scene, what: &str, lo: Vec3, hi: Vec3, rays: usize) -> usize {
    let mut seed = 0x70_u64;
    let mut hits = 0;
    let mut all = Vec::with_capacity(rays);
    for k in 0..rays {
        let o = lo + (hi - lo) * Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed));
        let d = Vec3::new(lcg(&mut seed), lcg(&mut seed), lcg(&mut seed)) - 0.5;
        let mut ray = Ray::new(o, d);
        if k % 3 == 0 {
            ray.t_max = lcg(&mut seed) * 4.0;
        }
        let mut ctx = QueryCtx::default();
        let want = closest_by_loop(s, &ray, &mut ctx);
        let got = s
            .top
            .closest(&s.objects, &ray, &mut ctx)
            .map(|(i, h)| (i, h.hit.t));
        assert_eq!(got, want, "{what}: {ray:?}");
        let blocked = s.objects.iter().any(|o| o.occludes(&ray, &mut ctx));
        assert_eq!(
            s.top.occluded(&s.objects, &ray, &mut ctx),
            blocked,
            "{what}: {ray:?}"
        );
        hits += usize::from(want.is_some());
        all.push(ray);
    }
    for force_intervals in [false, true] {
        let mut ctx = QueryCtx {
            force_intervals,
            ..QueryCtx::default()
        };
        let blocked = s.top.occluded_batch(&s.objects, &all, &mut ctx);
        assert_eq!(blocked.len(), all.len());
        for (ray, &got) in all.iter().zip(&blocked) {
            let want = s.objects.iter().any(|o| o.occludes(ray, &mut ctx));
            assert_eq!(
                got, want,
                "{what}, occluded batch (intervals {force_intervals}): {ray:?}"
            );
        }
        let batch = s.top.closest_batch(&s.objects, &all, &mut ctx);
        assert_eq!(batch.len(), all.len());
        for (ray, got) in all.iter().zip(&batch) {
            let want = s.top.closest(&s.objects, ray, &mut ctx);
            // Debug prints every field, `-0.0` apart from `0.0`: bit for bit.
            assert_eq!(
                format!("{got:?}"),
                format!("{want:?}"),
                "{what}, batch (intervals {force_intervals}): {ray:?}"
            );
        }
    }
    hits
}

#[test]
fn top_level_equals_the_object_loop_on_every_example_scene() {
    let mut n = 0;
    for (p, s) in example_scenes() {
        let hits = check(
            &s,
            &p.display().to_string(),
            Vec3::splat(-6.0),
            Vec3::splat(6.0),
            3000,
        );
        assert!(hits > 300, "{}: {hits}", p.display());
        n += 1;
    }
    assert!(n >= 7);
}

#[test]
fn top_level_equals_the_object_loop_on_ten_thousand_spheres_with_ties() {
    let mut text = String::from(
        "[camera]\neye = [0, 0, 30]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 8\n\n\
         [material.a]\ndiffuse = [1, 0, 0]\n\n[material.b]\ndiffuse = [0, 1, 0]\n\n\
         [[object]]\ntype = \"plane\"\npoint = [0, -11, 0]\nnormal = [0, 1, 0]\nmaterial = \"a\"\n",
    );
    for i in 0..10_000 {
        let (x, y, z) = (i % 25, (i / 25) % 20, i / 500);
        text.push_str(&format!(
            "\n[[object]]\ntype = \"sphere\"\ncenter = [{}, {}, {}]\nradius = 0.3\nmaterial = \"{}\"\n",
            x as f32 - 12.0,
            y as f32 - 10.0,
            z as f32 - 10.0,
            if i % 2 == 0 { "a" } else { "b" }
        ));
        // Every 97th sphere twice: equal `t`, the later one must win.
        if i % 97 == 0 {
            text.push_str(&format!(
                "\n[[object]]\ntype = \"sphere\"\ncenter = [{}, {}, {}]\nradius = 0.3\nmaterial = \"b\"\n",
                x as f32 - 12.0,
                y as f32 - 10.0,
                z as f32 - 10.0
            ));
        }
    }
    let s = parse(&text, Path::new("spheres.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.objects.len() > 10_000);
    let hits = check(&s, "spheres", Vec3::splat(-14.0), Vec3::splat(14.0), 3000);
    assert!(hits > 1000, "{hits}");
}

/// Two instances of one mesh in the same place (the later declared must win every equal `t`)
/// and a third moved by a transform, behind a plane: the batch query equals the single one.
#[test]
fn batch_equals_single_rays_on_coincident_mesh_instances() {
    let dir = scenes_dir();
    let text = format!(
        "[camera]\neye = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 40\nwidth = 8\nheight = 8\n\n\
         [material.a]\ndiffuse = [1, 0, 0]\n\n[material.b]\ndiffuse = [0, 1, 0]\n\n\
         [mesh.spot]\nfile = \"{}\"\n\n\
         [[object]]\ntype = \"plane\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\nmaterial = \"a\"\n\n\
         [[object]]\ntype = \"mesh\"\nmesh = \"spot\"\nmaterial = \"a\"\n\n\
         [[object]]\ntype = \"mesh\"\nmesh = \"spot\"\nmaterial = \"b\"\n\n\
         [[object]]\ntype = \"mesh\"\nmesh = \"spot\"\nmaterial = \"b\"\n\
         transform = [{{ rotate = {{ axis = [0, 1, 0], degrees = 30 }} }}, {{ translate = [0.3, 0, 0] }}]\n",
        dir.join("meshes/spot.obj").display()
    );
    let s = parse(&text, &dir.join("coincident.toml")).unwrap_or_else(|e| panic!("{e}"));
    let hits = check(&s, "coincident", Vec3::splat(-2.0), Vec3::splat(2.0), 4000);
    assert!(hits > 1000, "{hits}");
}

/// Rows traced as batches give the image of single rays, bit for bit, in every mode that
/// batches, on every example scene (small, so that the test stays quick).
#[test]
fn batched_rows_render_the_single_ray_image() {
    let mut n = 0;
    for (p, mut s) in example_scenes() {
        (s.camera.width, s.camera.height) = (48, 36);
        for mode in [Mode::Color, Mode::Normal, Mode::Depth, Mode::Barycentric] {
            let opts = RenderOptions {
                mode,
                ..RenderOptions::default()
            };
            let batched = render(&s, &opts);
            let single = render(
                &s,
                &RenderOptions {
                    single_rays: true,
                    ..opts
                },
            );
            let bits = |r: &halfray::render::Rendered| {
                r.pixels
                    .iter()
                    .flat_map(|p| p.to_array().map(f32::to_bits))
                    .collect::<Vec<u32>>()
            };
            assert!(
                bits(&batched) == bits(&single),
                "{} ({mode:?})",
                p.display()
            );
            assert_eq!(
                format!("{:?}", batched.counts),
                format!("{:?}", single.counts),
                "{} ({mode:?})",
                p.display()
            );
        }
        n += 1;
    }
    assert!(n >= 7);
}

/// A scene of one mesh and a plane; a row's shadow rays towards a point light, as the
/// renderer batches them
/// (`Tracer::plain_shadow_ray`, `Tracer::occluded_batch`): blocked exactly where the single
/// ray is and where the object loop says so, and walked in packets (fewer node tests than
/// the single rays take).
#[test]
fn a_row_s_shadow_rays_batched_answer_as_single_rays() {
    use halfray::render::plan::EffectPlan;
    use halfray::render::trace::Tracer;
    let dir = scenes_dir();
    let text = format!(
        "[camera]\neye = [0.4, 0.9, 2.2]\nlook_at = [0, 0.1, 0]\nfov = 40\nwidth = 768\nheight = 576\n\n\
         [material.a]\ndiffuse = [1, 0, 0]\n\n[mesh.spot]\nfile = \"{}\"\n\n\
         [[light]]\ntype = \"point\"\nposition = [1.5, 3.0, 1.0]\nintensity = 10\n\n\
         [[object]]\ntype = \"plane\"\npoint = [0, -0.75, 0]\nnormal = [0, 1, 0]\nmaterial = \"a\"\n\n\
         [[object]]\ntype = \"mesh\"\nmesh = \"spot\"\nmaterial = \"a\"\n",
        dir.join("meshes/spot.obj").display()
    );
    let s = parse(&text, &dir.join("shadow-rows.toml")).unwrap_or_else(|e| panic!("{e}"));
    // One bounded object (the batches send it every ray without a walk): the batch queries
    // against the object loop and the single-ray query.
    let hits = check(&s, "one mesh", Vec3::splat(-1.5), Vec3::splat(1.5), 3000);
    assert!(hits > 1000, "{hits}");
    let plan = EffectPlan::derive(&s, false);
    let tracer = Tracer {
        scene: &s,
        plan: &plan,
    };
    let (mut batch_nodes, mut shuffled_nodes, mut rays_seen, mut blocked_seen) = (0, 0, 0, 0);
    for j in (0..s.camera.height).step_by(24) {
        let primary: Vec<Ray> = (0..s.camera.width)
            .map(|i| s.camera.ray_at(i as f32 + 0.5, j as f32 + 0.5))
            .collect();
        let hits = tracer.closest_batch(&primary, &mut tracer.ctx());
        let rays: Vec<Ray> = hits
            .iter()
            .flatten()
            .filter_map(|sh| tracer.plain_shadow_ray(0, sh))
            .collect();
        let mut ctx = tracer.ctx();
        let got = tracer.occluded_batch(&rays, &mut ctx);
        batch_nodes += ctx.stats.nodes_visited;
        assert_eq!(got.len(), rays.len());
        // The same rays in a random order (no packets share leaves): as many answers, each
        // the answer of its ray in the row's order.
        let mut order: Vec<usize> = (0..rays.len()).collect();
        let mut seed = u64::from(j) + 1;
        for k in (1..order.len()).rev() {
            order.swap(k, (lcg(&mut seed) * (k + 1) as f32) as usize % (k + 1));
        }
        let shuffled: Vec<Ray> = order.iter().map(|&k| rays[k]).collect();
        let mut ctx = tracer.ctx();
        let got_shuffled = tracer.occluded_batch(&shuffled, &mut ctx);
        shuffled_nodes += ctx.stats.nodes_visited;
        assert_eq!(got_shuffled.len(), rays.len());
        for (&k, &g) in order.iter().zip(&got_shuffled) {
            assert_eq!(g, got[k], "row {j}: ray {k} shuffled");
        }
        for (ray, &got) in rays.iter().zip(&got) {
            let mut ctx = tracer.ctx();
            let want = tracer.occluded(ray, &mut ctx);
            let by_loop = s.objects.iter().any(|o| o.occludes(ray, &mut ctx));
            assert_eq!((got, got), (want, by_loop), "row {j}: {ray:?}");
            blocked_seen += usize::from(got);
        }
        rays_seen += rays.len();
    }
    assert!(
        rays_seen > 2000 && blocked_seen > 200,
        "{rays_seen} rays, {blocked_seen} blocked"
    );
    assert!(
        2 * batch_nodes < shuffled_nodes,
        "packets: {batch_nodes} node tests against {shuffled_nodes} shuffled"
    );
}

/// Shadow rays from one point towards the points of a disk (an area light's), and segments
/// ending exactly on the objects' box corners and faces (where a ray's own box test is
/// decided by its padding): the objects looked up once for the bundle's box
/// (`TopLevel::bounded_in`) block each ray exactly where the object loop says it is blocked.
#[test]
fn an_area_light_s_bundle_answers_as_the_object_loop() {
    let mut seed = 0xA7EA_u64;
    let mut bundles = 0;
    let mut looked_up = 0;
    for (p, s) in example_scenes() {
        let corners: Vec<Vec3> = s
            .objects
            .iter()
            .filter_map(|o| o.bounds)
            .filter(|b| b.is_finite())
            .flat_map(|b| {
                (0..8).map(move |k| {
                    let pick = |bit: i32, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
                    Vec3::new(
                        pick(1, b.min.x, b.max.x),
                        pick(2, b.min.y, b.max.y),
                        pick(4, b.min.z, b.max.z),
                    )
                })
            })
            .collect();
        let mut r = || lcg(&mut seed);
        for bundle in 0..300 {
            let origin = Vec3::new(r(), r(), r()) * 12.0 - 6.0;
            let targets: Vec<Vec3> = if bundle % 3 == 0 && !corners.is_empty() {
                // Box corners and points on box faces, as targets.
                (0..16)
                    .map(|_| {
                        let c = corners[(r() * corners.len() as f32) as usize % corners.len()];
                        if r() < 0.5 {
                            c
                        } else {
                            c + Vec3::new(r() - 0.5, 0.0, 0.0) * 1e-3
                        }
                    })
                    .collect()
            } else {
                let centre = Vec3::new(r(), r(), r()) * 12.0 - 6.0;
                let radius = [0.0, 0.05, 0.9, 3.0][bundle % 4];
                (0..16)
                    .map(|_| centre + (Vec3::new(r(), r(), r()) - 0.5) * (2.0 * radius))
                    .collect()
            };
            let hull = targets
                .iter()
                .fold(halfray_core::Aabb::new(origin, origin), |b, &t| b.grow(t));
            for max in [usize::MAX, 4] {
                let Some(near) = s.top.bounded_in(&hull, max) else {
                    assert_eq!(max, 4, "unlimited lookups always answer");
                    continue;
                };
                looked_up += 1;
                for &t in &targets {
                    let ray = halfray_core::shadow_segment(origin, t);
                    let mut ctx = QueryCtx::default();
                    let want = s.objects.iter().any(|o| o.occludes(&ray, &mut ctx));
                    let got = s.top.occluded_among(&s.objects, &near, &ray, &mut ctx);
                    assert_eq!(got, want, "{}: {ray:?} near {near:?}", p.display());
                }
            }
            bundles += 1;
        }
    }
    assert!(
        bundles >= 2100 && looked_up > bundles,
        "{bundles} bundles, {looked_up} lookups"
    );
}
