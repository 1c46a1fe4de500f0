//! Picks the memory map of the QEMU machine the target runs on and links with cortex-m-rt's
//! `link.x`: `mps2-an386` for thumbv7em-none-eabihf (4 MiB code at 0, 4 MiB RAM at
//! 0x2000_0000), `lm3s6965evb` for thumbv7m-none-eabi (256 KiB flash, 64 KiB RAM).
use std::path::PathBuf;

fn main() {
    let target = std::env::var("TARGET").unwrap_or_default();
    let memory = match target.as_str() {
        "thumbv7em-none-eabihf" => {
            "MEMORY {\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  RAM : ORIGIN = 0x20000000, LENGTH = 4M\n}\n"
        }
        "thumbv7m-none-eabi" => {
            "MEMORY {\n  FLASH : ORIGIN = 0x00000000, LENGTH = 256K\n  RAM : ORIGIN = 0x20000000, LENGTH = 64K\n}\n"
        }
        other => panic!(
            "mcu-firmware builds for thumbv7em-none-eabihf or thumbv7m-none-eabi, not `{other}`"
        ),
    };
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    std::fs::write(out.join("memory.x"), memory).expect("writing memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rerun-if-changed=build.rs");
}
