# Sourced by scripts/test-mcu.sh and scripts/test-ffi.sh: bakes the meshes the images query
# from flash and computes on the host the lines the images must print. Sets
#
#   baked    the directory of the baked files (examples/mcu/target/baked)
#   halfray  the release `halfray` binary; images: where cargo puts the mcu images
#   host     mcu-host's lines (`mcu:`, `mcu-query:`, `mcu-c:` per machine)
#
# and exports MCU_BAKED_M4F, MCU_BAKED_M3 (Rust sources) and MCU_C_BAKED, MCU_C_RAYS (the
# Cortex-M4F's mesh as `halfray bake --format bin`, and its query image's rays as HalfrayRay
# records, for the C firmware and the host C test).
manifest=examples/mcu/Cargo.toml
# The torus (4 608 triangles) for the Cortex-M4F; for the Cortex-M3's 256 KiB of flash, the
# octahedron subdivided three times (512 triangles).
baked=$PWD/examples/mcu/target/baked
mkdir -p "$baked"
cargo build -q --release -p halfray
# Where cargo puts what it builds: CARGO_TARGET_DIR when set (for the workspace and for the
# images alike), else each workspace's own target/.
halfray=${CARGO_TARGET_DIR:-$PWD/target}/release/halfray
images=${CARGO_TARGET_DIR:-$PWD/examples/mcu/target}
"$halfray" bake scenes/meshes/torus.obj -o "$baked/torus.rs" >&2
"$halfray" bake scenes/meshes/torus.obj -o "$baked/torus.bin" --format bin >&2
"$halfray" mesh subdivide scenes/meshes/octahedron.obj --levels 3 -o "$baked/octahedron-3.obj" >/dev/null
"$halfray" bake "$baked/octahedron-3.obj" -o "$baked/octahedron-3.rs" >&2
export MCU_BAKED_M4F=$baked/torus.rs MCU_BAKED_M3=$baked/octahedron-3.rs
export MCU_C_BAKED=$baked/torus.bin MCU_C_RAYS=$baked/rays-m4f.bin
host=$(cargo run -q --release --manifest-path "$manifest" -p mcu-host)
