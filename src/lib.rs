//! # neumann
//!
//! A physically based Monte Carlo renderer. It solves the rendering equation `L = Lₑ + T L` by
//! sampling its Neumann series `L = Σₖ Tᵏ Lₑ` with unbiased estimators
//! `F_N = 1/N Σ f(Xᵢ) / p(Xᵢ)`.
//!
//! Layers, each depending only on those above it in this list (`tests/layers.rs` enforces it):
//!
//! - [`choice`]: named options (`FromStr`/`Display` from one list per enum).
//! - [`math`]: vectors, colors, frames, transforms, bounds, rays, floating-point error bounds.
//! - [`props`]: plugin objects with typed, located properties (what loaders produce and plugins
//!   construct themselves from); located scene errors.
//! - [`image`]: images in memory (linear RGB).
//! - [`tensor`]: tensor files in memory (named n-dimensional arrays: measured BSDFs).
//! - [`sampling`]: warps (`sample` / `pdf` / `invert`), discrete and tabulated distributions,
//!   MIS heuristics, the RNG and the samplers.
//! - [`testkit`]: the statistical harness (χ², Kolmogorov–Smirnov, quadrature) that every
//!   sampler, BSDF and light is tested with.
//! - [`estimators`]: small Monte Carlo estimators from the lecture material (irradiance under a
//!   uniform sky) with their error analysis.
//! - [`geometry`], [`bvh`]: shapes, intersection with error bounds, area sampling; the BVH.
//! - [`texture`], [`material`], [`light`], [`medium`]: textures; BSDFs, emitters and light
//!   samplers, media (closed enums).
//! - [`camera`], [`scene`]: cameras; the runtime scene and its builder; the built-in Cornell box.
//! - [`integrator`]: the `Integrator` trait, the shared tracing core and the integrators.
//! - [`film`], [`render`]: accumulation, metrics and image files; the parallel render driver.
//! - [`load`]: scene formats (Mitsuba 3 XML) and the files they name (meshes, images).

#![warn(missing_docs)]

pub mod bvh;
pub mod camera;
pub mod choice;
pub mod estimators;
pub mod film;
pub mod geometry;
pub mod image;
pub mod integrator;
pub mod light;
pub mod load;
pub mod material;
pub mod math;
pub mod medium;
pub mod props;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod tensor;
pub mod testkit;
pub mod texture;
