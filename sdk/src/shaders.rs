//! Embedded SPIR-V, compiled from shaders/ by build.rs.
#![allow(dead_code)]
include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
