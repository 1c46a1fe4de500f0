//! Half-edge bench: build time, Loop subdivision time per level, bytes per element.
//!
//! ```sh
//! cargo run --release -p halfray-core --example halfedge_bench -- ../shared/meshes/bunny.obj [levels]
//! ```
//! Storage is heap `Vec`s lent to [`SliceMesh`]es, so nothing large sits on the stack.

#[path = "common/obj.rs"]
mod obj;

use obj::load;
use std::time::Instant;

use halfray_core::halfedge::{
    Counts, EdgeRec, FaceRec, HalfedgeRec, LoopWeights, Mesh, SliceMesh, VertexRec,
    build_scratch_len,
};

/// Repetitions of each timed step; the minimum time is reported.
const REPS: usize = 5;

/// A mesh over leaked heap buffers (the bench process is short-lived).
fn mesh_with(c: Counts) -> SliceMesh<'static> {
    Mesh::from_slices(
        vec![VertexRec::EMPTY; c.vertices].leak(),
        vec![EdgeRec::EMPTY; c.edges].leak(),
        vec![FaceRec::EMPTY; c.faces].leak(),
    )
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn bytes(n: Counts) -> usize {
    n.vertices * size_of::<VertexRec>()
        + n.edges * size_of::<EdgeRec>()
        + n.faces * size_of::<FaceRec>()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .unwrap_or_else(|| "../shared/meshes/bunny.obj".into());
    let levels: usize = args.next().map_or(2, |s| s.parse().expect("levels"));
    let (p, t) = load(&path);
    println!("mesh {path}: {} vertices, {} triangles", p.len(), t.len());
    println!(
        "bytes per element: vertex {} (position + outgoing halfedge), halfedge {}, edge {} (its 2 halfedges; twins implicit), face {}",
        size_of::<VertexRec>(),
        size_of::<HalfedgeRec>(),
        size_of::<EdgeRec>(),
        size_of::<FaceRec>()
    );

    let mut m = mesh_with(Counts {
        vertices: p.len(),
        edges: 3 * t.len(),
        faces: t.len(),
    });
    let mut scratch = vec![0u32; build_scratch_len(t.len())];
    let mut best = f64::INFINITY;
    for _ in 0..REPS {
        let t0 = Instant::now();
        m.build(&p, &t, &mut scratch).expect("build");
        best = best.min(ms(t0));
    }
    let t0 = Instant::now();
    m.validate().expect("validate");
    let val = ms(t0);
    let n = m.len();
    println!(
        "build: {best:.2} ms (min of {REPS}); validate {val:.2} ms; V {} E {} F {}; {:.1} B per vertex, {:.2} MB",
        n.vertices,
        n.edges,
        n.faces,
        bytes(n) as f64 / n.vertices as f64,
        bytes(n) as f64 / 1e6
    );

    for level in 1..=levels {
        let need = m.len().after_loop();
        let mut out = mesh_with(need);
        let mut best = f64::INFINITY;
        for _ in 0..REPS {
            let t0 = Instant::now();
            m.subdivide_loop(&mut out, LoopWeights::Warren)
                .expect("subdivide");
            best = best.min(ms(t0));
        }
        let t0 = Instant::now();
        out.validate().expect("validate");
        let val = ms(t0);
        let n = out.len();
        println!(
            "loop level {level}: {best:.2} ms (min of {REPS}); validate {val:.2} ms; V {} E {} F {}; {:.2} MB",
            n.vertices,
            n.edges,
            n.faces,
            bytes(n) as f64 / 1e6
        );
        m = out;
    }
}
