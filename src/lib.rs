//! # neumann
//!
//! A physically based Monte Carlo renderer. It solves the rendering equation `L = Lₑ + T L` by
//! sampling its Neumann series `L = Σₖ Tᵏ Lₑ` with unbiased estimators
//! `F_N = 1/N Σ f(Xᵢ) / p(Xᵢ)`.
//!
//! Layers, each depending only on those above it in this list:
//!
//! - [`choice`]: named options (`FromStr`/`Display` from one list per enum).
//! - [`math`]: vectors, colors, frames, transforms, bounds, rays, floating-point error bounds.
//! - [`sampling`]: warps (`sample` / `pdf` / `invert`), discrete and tabulated distributions,
//!   MIS heuristics, the RNG and the samplers.
//! - [`testkit`]: the statistical harness (χ², Kolmogorov–Smirnov, quadrature) that every
//!   sampler, BSDF and light is tested with.
//! - [`estimators`]: small Monte Carlo estimators from the lecture material (irradiance under a
//!   uniform sky) with their error analysis.
//! - [`geometry`], [`bvh`]: shapes, intersection with error bounds, area sampling; the BVH.
//! - [`texture`], [`material`], [`light`]: textures; BSDFs and emitters (closed enums).
//! - [`camera`], [`scene`]: cameras; the runtime scene and its builder; built-in scenes.
//! - [`load`]: mesh files (OBJ, PLY).
//! - [`integrator`]: the `Integrator` trait and the path tracer.
//! - [`film`], [`render`]: accumulation and image files; the parallel render driver.

#![warn(missing_docs)]

pub mod bvh;
pub mod camera;
pub mod choice;
pub mod estimators;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod load;
pub mod material;
pub mod math;
pub mod medium;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod testkit;
pub mod texture;
