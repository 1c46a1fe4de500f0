//! The scene file as written: serde types with spans, `deny_unknown_fields` everywhere.
//! Semantic checks (required fields per type, ranges, names) happen in `build`.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

/// A spanned value.
pub type S<T> = Spanned<T>;
/// A spanned 3-vector of spanned components (a bad component is reported at its place).
pub type V3 = S<Exact<S<f32>, 3>>;

/// A fixed-size array that refuses extra elements: serde's `[T; N]` reads the first `N` and
/// ignores the rest (`center = [0, 0, 0, "junk"]` was accepted), this reports "invalid length".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact<T, const N: usize>(pub [T; N]);

impl<T: Copy + Default, const N: usize> Default for Exact<T, N> {
    fn default() -> Self {
        Self([T::default(); N])
    }
}

impl<T, const N: usize> std::ops::Deref for Exact<T, N> {
    type Target = [T; N];
    fn deref(&self) -> &[T; N] {
        &self.0
    }
}

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> serde::de::Visitor<'de> for V<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "an array of exactly {N} elements")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Exact<T, N>, A::Error> {
                let mut out = Vec::with_capacity(N);
                for k in 0..N {
                    out.push(
                        a.next_element()?
                            .ok_or_else(|| serde::de::Error::invalid_length(k, &self))?,
                    );
                }
                let mut extra = 0usize;
                while a.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(serde::de::Error::invalid_length(N + extra, &self));
                }
                let out = out
                    .try_into()
                    .map_err(|_| serde::de::Error::invalid_length(0, &self))?;
                Ok(Exact(out))
            }
        }
        d.deserialize_seq(V::<T, N>(std::marker::PhantomData))
    }
}

/// The whole file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDef {
    pub ambient: Option<V3>,
    pub background: Option<V3>,
    pub max_depth: Option<S<u32>>,
    pub samples: Option<S<u32>>,
    pub camera: S<CameraDef>,
    #[serde(default)]
    pub light: Vec<S<LightDef>>,
    #[serde(default)]
    pub material: BTreeMap<String, S<MaterialDef>>,
    #[serde(default)]
    pub mesh: BTreeMap<String, S<MeshDef>>,
    #[serde(default)]
    pub object: Vec<S<ObjectDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    #[serde(rename = "type")]
    pub kind: Option<S<String>>,
    pub eye: V3,
    pub look_at: V3,
    pub up: Option<V3>,
    pub fov: Option<S<f32>>,
    pub view_size: Option<S<f32>>,
    pub width: S<u32>,
    pub height: S<u32>,
    pub aperture: Option<S<f32>>,
    pub focus_distance: Option<S<f32>>,
    pub lens_samples: Option<S<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub position: Option<V3>,
    pub direction: Option<V3>,
    pub color: Option<V3>,
    pub intensity: Option<S<f32>>,
    pub cast_shadows: Option<bool>,
    pub name: Option<String>,
    pub radius: Option<S<f32>>,
    pub samples: Option<S<u32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialDef {
    pub ambient: Option<V3>,
    pub diffuse: Option<V3>,
    pub specular: Option<V3>,
    pub shininess: Option<S<f32>>,
    pub specular_model: Option<S<String>>,
    pub mirror: Option<S<f32>>,
    pub transparency: Option<S<f32>>,
    pub ior: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshDef {
    pub file: S<String>,
    pub subdivide: Option<S<u32>>,
    pub smooth: Option<S<SmoothDef>>,
    pub shading: Option<S<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SmoothDef {
    pub step: S<f32>,
    pub iterations: S<u32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadricDef {
    pub xx: Option<S<f32>>,
    pub yy: Option<S<f32>>,
    pub zz: Option<S<f32>>,
    pub xy: Option<S<f32>>,
    pub xz: Option<S<f32>>,
    pub yz: Option<S<f32>>,
    pub x: Option<S<f32>>,
    pub y: Option<S<f32>>,
    pub z: Option<S<f32>>,
    pub c: Option<S<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateDef {
    pub axis: V3,
    pub degrees: S<f32>,
}

/// `scale = 2` (one factor for every axis, spanned by the step's `scale`) or
/// `scale = [sx, sy, sz]` (each factor spanned, so a bad one is reported at its place).
pub enum ScaleDef {
    /// One factor for all three axes.
    Uniform(f32),
    /// One factor per axis.
    Axes([S<f32>; 3]),
}

impl<'de> Deserialize<'de> for ScaleDef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ScaleDef;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number or an array of 3 numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<ScaleDef, E> {
                Ok(ScaleDef::Uniform(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<ScaleDef, E> {
                Ok(ScaleDef::Uniform(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<ScaleDef, E> {
                Ok(ScaleDef::Uniform(v as f32))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<ScaleDef, A::Error> {
                let mut axis = |k: usize| {
                    a.next_element()?
                        .ok_or_else(|| serde::de::Error::invalid_length(k, &self))
                };
                let out = [axis(0)?, axis(1)?, axis(2)?];
                if a.next_element::<f32>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &self));
                }
                Ok(ScaleDef::Axes(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// One step of a transform list; exactly one field is set.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformDef {
    pub translate: Option<V3>,
    pub rotate: Option<S<RotateDef>>,
    pub scale: Option<S<ScaleDef>>,
    pub matrix: Option<S<Exact<Exact<f32, 4>, 4>>>,
}

/// An object (or CSG operand). Which fields are required or allowed depends on `type`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDef {
    #[serde(rename = "type")]
    pub kind: S<String>,
    pub material: Option<S<String>>,
    pub center: Option<V3>,
    pub radius: Option<S<f32>>,
    pub radii: Option<V3>,
    pub point: Option<V3>,
    pub normal: Option<V3>,
    pub vertices: Option<S<Vec<V3>>>,
    pub min: Option<V3>,
    pub max: Option<V3>,
    pub coefficients: Option<S<QuadricDef>>,
    pub mesh: Option<S<String>>,
    pub op: Option<S<String>>,
    pub operands: Option<S<Vec<S<ObjectDef>>>>,
    pub transform: Option<S<Vec<S<TransformDef>>>>,
    pub repeat: Option<S<RepeatDef>>,
}

/// `repeat = { count = [nx, ny, nz], step = [dx, dy, dz], materials = [...] }` on a top-level
/// object: copies on a grid.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RepeatDef {
    pub count: S<Exact<u32, 3>>,
    pub step: V3,
    pub materials: Option<S<Vec<S<String>>>>,
}

impl ObjectDef {
    /// `(name, span)` of every type-specific field that is present.
    pub fn present_fields(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        let mut v = Vec::new();
        macro_rules! f {
            ($($name:ident),*) => {$(
                if let Some(x) = &self.$name {
                    v.push((stringify!($name), x.span()));
                }
            )*};
        }
        f!(
            center,
            radius,
            radii,
            point,
            normal,
            vertices,
            min,
            max,
            coefficients,
            mesh,
            op,
            operands
        );
        v
    }
}
