//! What can go wrong with Embree.

use super::ffi;
use std::fmt;

/// An error from setting up or using Embree.
#[derive(Debug, Clone, PartialEq)]
pub enum EmbreeError {
    /// The device configuration string holds a NUL byte.
    InvalidConfig(String),
    /// `rtcNewDevice` failed (code is an `RTCError`).
    DeviceCreation { code: u32, message: String },
    /// The runtime library is not Embree 4.4.x, whose ray/hit layout this module assumes.
    UnsupportedVersion { found: u32 },
    /// The library was built with `EMBREE_BACKFACE_CULLING`: it would not be a fair reference.
    BackfaceCulling,
    /// The start-up probe ray showed a ray/hit layout other than the one assumed.
    LayoutMismatch(String),
    /// An Embree call reported an error (code is an `RTCError`).
    Api {
        call: &'static str,
        code: u32,
        message: String,
    },
    /// The mesh cannot be handed to Embree (e.g. an index out of range).
    InvalidMesh(String),
}

impl fmt::Display for EmbreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidConfig(c) => {
                write!(f, "invalid Embree device config {c:?} (holds a NUL byte)")
            }
            Self::DeviceCreation { code, message } => {
                write!(
                    f,
                    "rtcNewDevice failed: {} ({code}): {message}",
                    ffi::error_name(*code)
                )
            }
            Self::UnsupportedVersion { found } => write!(
                f,
                "Embree {}.{}.{} found, but this build assumes the ray/hit layout of Embree 4.4.x \
                 (run scripts/setup-embree.sh and set EMBREE_DIR)",
                found / 10000,
                found / 100 % 100,
                found % 100
            ),
            Self::BackfaceCulling => {
                write!(
                    f,
                    "this Embree library was built with back-face culling; refusing to use it"
                )
            }
            Self::LayoutMismatch(m) => write!(f, "Embree ray/hit layout check failed: {m}"),
            Self::Api {
                call,
                code,
                message,
            } => {
                write!(
                    f,
                    "{call} failed: {} ({code}): {message}",
                    ffi::error_name(*code)
                )
            }
            Self::InvalidMesh(m) => write!(f, "invalid mesh for Embree: {m}"),
        }
    }
}

impl std::error::Error for EmbreeError {}
