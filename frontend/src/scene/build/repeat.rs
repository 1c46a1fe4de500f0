//! `repeat` on a top-level object: a grid of copies.

use crate::error::Result;
use crate::scene::def::{self, S};
use crate::scene::geom::Node;
use glam::Vec3;
use halfray_core::transform::Transform;

use super::Ctx;
use super::list;

/// Most objects a scene may hold, repeated copies included: 10⁶ (a copy costs a few hundred
/// bytes and one top-level BVH leaf; a mesh's triangles are shared by its copies).
pub const MAX_OBJECTS: usize = 1_000_000;

/// The copies `repeat` makes of `node` (object `p`): copy `(i, j, k)`, numbered
/// `i + nx·(j + ny·k)`, is `node` moved by `(i·dx, j·dy, k·dz)` after its own transform, with
/// material `materials[number mod len]` when given (on the copy and on every CSG operand that
/// inherits it, [`Node::with_material`]). `before` objects exist already (for
/// [`MAX_OBJECTS`]).
///
/// # Errors
///
/// A count of 0, more copies than [`MAX_OBJECTS`] allows, an unknown or empty `materials`,
/// or a copy whose translation overflows `f32` (named by its grid position, at `step`).
pub(super) fn repeat(
    ctx: &Ctx<'_>,
    node: &Node,
    r: &S<def::RepeatDef>,
    p: &str,
    before: usize,
) -> Result<Vec<Node>> {
    let rd = r.get_ref();
    let f = |name: &str| format!("{p}.repeat.{name}");
    let [nx, ny, nz] = rd.count.get_ref().0;
    if nx == 0 || ny == 0 || nz == 0 {
        return Err(ctx.err(&rd.count.span(), &f("count"), "every count must be ≥ 1"));
    }
    // Checked: a product that does not fit in 64 bits is over the limit too.
    let total = u64::from(nx)
        .checked_mul(u64::from(ny))
        .and_then(|p| p.checked_mul(u64::from(nz)));
    let room = (MAX_OBJECTS - before.min(MAX_OBJECTS)) as u64;
    let Some(total) = total.filter(|&t| t <= room) else {
        let copies = total.map_or_else(
            || format!("{nx} × {ny} × {nz} copies (more than 2^64)"),
            |t| format!("{t} copies"),
        );
        return Err(ctx.err(
            &rd.count.span(),
            &f("count"),
            format!("{copies}: more than {MAX_OBJECTS} objects in the scene"),
        ));
    };
    let step = ctx.v3(&rd.step, &f("step"))?;
    let materials = match &rd.materials {
        None => vec![node.material],
        Some(names) if names.get_ref().is_empty() => {
            return Err(ctx.err(
                &names.span(),
                &f("materials"),
                "must name at least one material",
            ));
        }
        Some(names) => names
            .get_ref()
            .iter()
            .map(|m| {
                ctx.materials.get(m.get_ref()).copied().ok_or_else(|| {
                    let known: Vec<&str> = ctx.materials.keys().map(String::as_str).collect();
                    ctx.err(
                        &m.span(),
                        &f("materials"),
                        format!(
                            "no material named `{}` (defined: {})",
                            m.get_ref(),
                            list(&known)
                        ),
                    )
                })
            })
            .collect::<Result<Vec<u32>>>()?,
    };
    let mut out = Vec::with_capacity(total as usize);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let offset = step * Vec3::new(i as f32, j as f32, k as f32);
                // The object's own transform is invertible and a translation leaves its
                // linear part alone, so a copy fails only where the translation (the copy's
                // or its inverse's) leaves the finite range of `f32`.
                let moved = Transform::translate(offset)
                    .and_then(|t| match &node.transform {
                        Some(own) => own.then(&t),
                        None => Ok(t),
                    })
                    .map_err(|_| {
                        ctx.err(
                            &rd.step.span(),
                            &f("step"),
                            format!(
                                "copy ({i}, {j}, {k}): the translation overflows: step × ({i}, {j}, {k}) after the object's own transform leaves f32's range (±{:.1e}) for the copy or its inverse",
                                f32::MAX
                            ),
                        )
                    })?;
                let material = materials[out.len() % materials.len()];
                let copy = node.with_material(material);
                out.push(Node::new(copy.shape, material, Some(moved)));
            }
        }
    }
    Ok(out)
}
