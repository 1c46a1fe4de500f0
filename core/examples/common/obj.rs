//! The examples' OBJ reader: `v` and triangular `f` lines only (the first three indices of
//! a face, texture and normal indices dropped); panics on a malformed file (examples only).

use halfray_core::Vec3;

/// Positions and 0-based triangles of the OBJ file at `path`.
pub fn load(path: &str) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let (mut p, mut t) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f32> = it.take(3).map(|x| x.parse().expect("bad float")).collect();
                p.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let c: Vec<u32> = it
                    .take(3)
                    .map(|x| {
                        x.split('/')
                            .next()
                            .unwrap_or("")
                            .parse::<u32>()
                            .expect("bad index")
                            - 1
                    })
                    .collect();
                t.push([c[0], c[1], c[2]]);
            }
            _ => {}
        }
    }
    (p, t)
}
