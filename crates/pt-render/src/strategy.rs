//! The sampling strategy a scene renders with by default, chosen from what
//! the scene is (docs/ARCHITECTURE.md, "Per-scene defaults").
//!
//! Three features decide:
//! - how large the light looks from the room: the mean over the room's
//!   surfaces of `1 - cos` of the half angle of the light's cone (its solid
//!   angle over 2 pi), [`light_extent`];
//! - how bright the room is: the area-weighted mean albedo of its surfaces,
//!   [`mean_albedo`];
//! - where those two do not settle the glow lobe, a pilot: small CPU
//!   renders of the scene with the lobe off, at a tenth and at a quarter,
//!   whose spread gives each one's relMSE per sample, [`glow_pilot`].
//!
//! The glow lobe (`pt_core::light::GlowLobe`) sends a share of the BSDF
//! samples toward the light's bright surroundings. Around a small light in
//! a room of middling albedo those outshine the rest of the room, which the
//! cosine lobe rarely finds, and a quarter of the samples go there
//! (`GLOW_PROBABILITY`). Around a large light, or in a bright room, what
//! the lobe finds depends on the walls and spheres beside the light, their
//! colours and what the camera sees of them; no bound on a feature of the
//! scene held on every room measured, and the pilot measures it instead:
//! the lobe at a quarter or a tenth (`FLAG_GLOW_SPARSE`), whichever leaves
//! less noise, where it cuts the noise per sample enough to pay for its
//! cost per sample ([`PILOT_LOBE_RATIO`]), else none.
//! `pathtracer bench convergence --suite` measured the thresholds: see
//! [`GLOW_MAX_EXTENT`], [`GLOW_MAX_ALBEDO`] and [`PILOT_LOBE_RATIO`].
//!
//! Where no wall can shadow the light (a convex room around it, which is
//! every scene of the suite), connections through lit wall points
//! (`FLAG_CONNECT`) take the glow lobe's place around a light that looks
//! small from the room ([`GLOW_MAX_EXTENT`]): they find the light's bright
//! surroundings by construction, and there those outshine the rest of the
//! room. Around a large light its surroundings are no brighter than the
//! rest of the room, and the connections' extra rays and draws cost more
//! than they save, on both backends: on the CPU they took 1.2x to 1.7x the
//! glow lobe's time to relMSE 1e-3 around the suite's large lights, and on
//! lavapipe, with the kernel's entry points without the connections' code
//! where a render makes none, 1.24x to 1.54x the glow-lobe rule's time on
//! the seven lights of radius 0.19 to 0.5. Around the small lights they
//! won on both (0.72x to 0.90x on the CPU; on lavapipe 0.66x to 0.93x, and
//! the glow-lobe rule never
//! reached 1e-3 within twice their time around the tiny light). One small
//! light went the other way on both: the low light beside the spheres,
//! near the room's open side, where a third of the directions from the
//! light meet a sphere or leave the room before any wall, and connections
//! find nothing along them ([`wall_share`], [`CONNECT_MIN_WALL_SHARE`];
//! docs/ARCHITECTURE.md, "Per-scene defaults", has the measurements).
//!
//! With connections on, two more choices follow:
//! - every draw of a path comes from the Sobol sequence
//!   (`FLAG_SOBOL_DEEP`): a connection draws four more numbers per vertex
//!   (a direction about the light's centre, a light sample at the wall
//!   point), so the first five Sobol draws no longer reach past the first
//!   vertex, and with connections Sobol for every draw reached relMSE
//!   1e-3 sooner on every scene of the suite, on both backends;
//! - a light in a corner or against an edge, near enough to two walls or
//!   more to light a bright spot on each ([`hot_walls`],
//!   [`CORNER_MIN_HOT_SPOT`]), keeps the glow lobe beside the connections
//!   ([`CORNER_WALLS`]): at a quarter where the cooler of its two hottest
//!   walls is very hot ([`CORNER_QUARTER_HOT_SPOT`]), else at a tenth;
//! - a light right beside a sphere, whose nearest side it makes hot
//!   ([`sphere_hot_spot`], [`SPHERE_HOT_SPOT`]), takes the glow lobe at a
//!   quarter: the connections reach walls only. Where a wall is hot too
//!   ([`WALL_HOT_SPOT`]) the lobe joins the connections, else it takes
//!   their place.
//!
//! A sphere near the light makes the light look larger from the room
//! ([`light_extent`] averages over the spheres' surfaces too), and the
//! pilot decides for it as for any light that looks large.
//!
//! The glow-lobe rule above is the rule for the rest: rooms where some
//! wall shadows the light ([`connections_apply`]), and large lights.
//!
//! Every rule samples NEE uniformly in the light's cone, with the control
//! variate that makes its estimate exact where the light is wholly visible
//! ([`BASE_FLAGS`]).
//!
//! Every choice is one of the unbiased configurations the accuracy suite
//! checks; only the noise differs.

use pt_core::glam::Vec3;
use pt_core::light::light_cone;
use pt_core::params::{
    FLAG_CONNECT, FLAG_GLOW, FLAG_GLOW_SPARSE, FLAG_LIGHT_EDGE, FLAG_MIS, FLAG_NEE_CONTROL, FLAG_NEE_PROJECTED,
    FLAG_SOBOL_DEEP, FLAGS_DEFAULT,
};
use pt_core::query::{Hit, HitKind};
use pt_core::ray::Ray;

use std::collections::HashMap;
use std::sync::{LazyLock, Mutex};

use crate::cpu::CpuRenderer;
use crate::scene::{RenderSettings, Scene};

/// The flags every rule below starts from: the project's defaults
/// (`FLAGS_DEFAULT`: NEE without MIS, the glow lobe at a quarter, Sobol for
/// the first draws) with NEE uniform in the light's cone, never by
/// projected solid angle (`FLAG_NEE_PROJECTED` off), and with the control
/// variate (`FLAG_NEE_CONTROL`). The control variate makes the estimate
/// exact where the light is wholly visible above the horizon, as
/// projection does, for a dot product and a select:
/// relMSE at 64 spp on the CPU fell 5% to 10% around the large lights
/// (radius 0.4 to 0.5), 2% to 3% around lights of radius 0.19 to 0.22, and
/// by up to 5% in the connected scenes, at the same time per sample.
/// Projecting makes the
/// shadow ray's estimate exact where the light is wholly visible, so it
/// leaves a little less noise per sample (in the default scene uniform
/// sampling's relMSE at 512 spp is 1.08x projection's), but it is a second sampling routine: where the scene is
/// compiled into the kernel (`TraceKernel::Specialized`, lavapipe's
/// default) a render without the flag drops that code, and on the CPU the
/// eight lanes run both routines wherever their vertices differ. Uniform
/// sampling reached relMSE 1e-3 sooner on both backends on most scenes of
/// the suite (docs/ARCHITECTURE.md, "Per-scene defaults"). Camera samples
/// take the light edge's control variate (`FLAG_LIGHT_EDGE`), which acts
/// only in the pixels the light's silhouette crosses.
pub const BASE_FLAGS: u32 = (FLAGS_DEFAULT & !FLAG_NEE_PROJECTED) | FLAG_NEE_CONTROL | FLAG_LIGHT_EDGE;

/// The largest light extent (mean `1 - cos` of the light's half angle over
/// the room's surfaces) at which the glow lobe takes a quarter of the BSDF
/// samples; above it, a tenth. Measured on the scene suite at 128x128
/// (relMSE at 128 spp on the CPU, 3 seeds; docs/PERFORMANCE.md): at extents
/// up to 0.008 (the default scene, 0.008; the corner light, 0.007; the
/// near-wall light, 0.005) a quarter is best among 0.05, 0.1, 0.15 and 0.25,
/// with relMSE 8% to 38% below a tenth's; at 0.028 (a light of radius 0.25
/// in the middle of the room), 0.032 (radius 0.3 below the ceiling) and
/// 0.093 (radius 0.5) a tenth is 7% to 17% below a quarter and 7% to 29%
/// below the cosine lobe alone.
pub const GLOW_MAX_EXTENT: f32 = 0.015;

/// The largest mean albedo of the room at which the glow lobe takes a
/// quarter of the BSDF samples. Measured on the scene suite at 128x128: in
/// the default scene (mean albedo 0.55) a quarter is best; in the same room
/// with every albedo 0.9 and 16 bounces (mean 0.89) a tenth is best (relMSE
/// at 128 spp 14% below the cosine lobe alone's and 33% below a quarter's).
/// The suite has no room in between: the threshold sits where the share of
/// light that has bounced more than once, about `a / (1 - a)` of the
/// once-bounced for albedo `a`, is halfway (geometrically) between the two,
/// 3.
pub const GLOW_MAX_ALBEDO: f32 = 0.75;

/// The largest ratio of the glow lobe's relMSE per sample to the relMSE
/// per sample without it, as the pilot measures them ([`glow_pilot`]), at
/// which a light that the lobe does not suit at a quarter outright
/// ([`glow_pays`]) keeps it. The lobe costs time per sample: measured with
/// `examples/strategy_probe.rs` (128x128, 64 spp, 6 seeds) around four
/// lights of radius 0.22 to 0.55, the lobe at a tenth took 1.03x to 1.13x
/// the time per sample of no lobe on lavapipe and 1.03x to 1.16x on the
/// CPU, about 1.08x on both, whose inverse is this bound. Over 55 rooms
/// whose light looks large (the suite's, the held-out, probe, sphere,
/// contact and random scenes, and rooms of `scripts/random_rooms.py` with
/// large lights near each wall), the pilot's ratios followed those of
/// `strategy_probe` (256 or 64 spp at 128x128, 4 to 12 seeds) within
/// about 0.05, and the lobe's measured ratio was 0.88 or below or 0.94 or
/// above on all but a few, which lie near the bound either way
/// (docs/ARCHITECTURE.md, "Per-scene defaults").
pub const PILOT_LOBE_RATIO: f64 = 0.92;

/// The largest ratio of the quarter's relMSE per sample to the tenth's, as
/// the pilot measures them, at which the lobe takes a quarter rather than a
/// tenth (both cost the same time per sample). Around 17 lights where both
/// were measured, the pilot's ratio read 0.04 lower on average than
/// `examples/strategy_probe.rs`'s at 64 to 256 spp (from 0.015 above to
/// 0.09 below): at the pilot's 16 samples per pixel the quarter looks a
/// little better than at the sample counts where renders reach relMSE
/// 1e-3. Where the pilot read 0.95 or below, the probe found the quarter
/// 0.93 to 0.97 of the tenth (or a tie); where it read above, 1.01 to 1.10.
pub const PILOT_QUARTER_RATIO: f64 = 0.95;

/// Pixels along the longer side of the pilot's images ([`glow_pilot`]);
/// the shorter side keeps the scene's aspect.
pub const PILOT_SIDE: u32 = 64;

/// Renders per strategy in the pilot, each on its own seed: the spread
/// between them gives the variance of every pixel.
pub const PILOT_RENDERS: u32 = 8;

/// Samples per pixel of each pilot render. Sobol's samples make the noise
/// per sample fall with the sample count; the time to relMSE 1e-3 at
/// 128x128 lies around 16 to 64 samples on most scenes, so the pilot
/// measures there: at 8 samples, the held-out light in the open read a
/// ratio 0.06 higher than at 16.
pub const PILOT_SPP: u32 = 16;

/// The pilot's first seed: apart from the seeds users and tests render.
const PILOT_SEED: u32 = 0x9170_0000;

/// The smallest hot spot ([`hot_spots`]) that makes a wall hot: the
/// light's power, spread from its centre, lights the wall's nearest point
/// at least this many times as brightly as the walls are lit on average.
/// The hot spot follows the distance from the light's centre, whatever the
/// light's radius: lights of the same power make the same spot. On the
/// connected small lights of the suite, the held-out scenes and
/// scenes/probe/, the second-hottest wall has 1.6 to 4.4 where the glow
/// lobe beside the connections cost time, on both backends
/// (1.13x to 1.43x), and 9.9 to 49 where it paid (the suite's corner
/// light, radius 0.12, its centre 0.18 from three walls: 1.09x on lavapipe
/// and 1.04x on the CPU in the latest suite run; a light
/// of radius 0.07, its centre 0.2 from the ceiling and 0.4 from two walls:
/// 1.19x on lavapipe and 1.16x on the CPU; with the share of
/// [`CORNER_QUARTER_HOT_SPOT`], a light along an edge with spots of 20 and
/// 18 took 0.98x and 0.95x the time of no lobe). The bound sits between,
/// geometrically. It replaced a bound in light radii (walls within 1.25
/// radii of the light), which left that small light out: 1.86 radii from
/// the ceiling, its centre is nearer the ceiling than the default light's
/// (0.3), one radius below it.
pub const CORNER_MIN_HOT_SPOT: f32 = 6.6;

/// How many hot walls ([`CORNER_MIN_HOT_SPOT`]) make a corner or an edge,
/// where the glow lobe stays on beside the connections. A light there
/// lights the walls right beside it far more brightly than the rest of
/// the room, and two hot walls meet along an edge that the connections,
/// which pick wall points by the light's directions, reach no more often
/// than any other: on the suite the corner light reached relMSE 1e-3 more
/// than twice as fast on both backends with the lobe beside the
/// connections when first measured (1.09x on lavapipe and 1.04x on the
/// CPU in the latest run), while around small lights with one hot wall or none the
/// lobe only cost time (docs/ARCHITECTURE.md, "Per-scene defaults", has
/// the figures).
pub const CORNER_WALLS: usize = 2;

/// The smallest corner spot ([`corner_hot_spot`], the second-hottest) at which a corner
/// or an edge takes the glow lobe at a quarter beside the connections;
/// below it, at a tenth (`FLAG_GLOW_SPARSE`). Set on three lights, by the
/// time to relMSE 1e-3 of a quarter against a tenth (docs/bench/probe.md,
/// docs/PERFORMANCE.md): the suite's corner light (spots of 49 on three
/// walls) took 0.92x the time with a quarter on lavapipe and 0.96x on the
/// CPU; a light of radius 0.07 near the back right corner (40, 9.9, 9.9)
/// 1.17x and 1.05x, and a light of radius 0.06 along the edge of the
/// ceiling and the left wall (20, 18) 1.13x and 1.18x, where the lobe at
/// a quarter took longer even than no lobe. The bound sits between 18 and
/// 49, geometrically; a tenth was within 1.09x of a quarter on all three.
pub const CORNER_QUARTER_HOT_SPOT: f32 = 29.0;

/// The smallest sphere spot ([`sphere_hot_spot`]) at which a sphere beside
/// the light outshines what the connections find, which reach walls only:
/// with no hot wall ([`WALL_HOT_SPOT`]) the connections give way to the
/// glow lobe at a quarter, and beside a hot wall the lobe joins them at a
/// quarter. Measured on rooms made at random (`scripts/random_rooms.py`,
/// `examples/strategy_probe.rs`; docs/ARCHITECTURE.md, "Per-scene
/// defaults"), by relMSE at 256 spp times the time per sample on the CPU:
/// around ten small lights with sphere spots of 13 to 382 and no wall
/// above 13, connections alone took 1.16x to 29x the time of the glow
/// lobe at a quarter without them, and the lobe beside them 1.10x to
/// 1.48x; around six with spots of 6.6 to 9.5, connections alone took
/// 0.61x to 0.99x the time of the lobe at a quarter. Farther than
/// [`SMALL_OPEN_CLEARANCE`] from every surface the lobe is off as well,
/// as for a small light of a low wall share: around three lights of
/// radius 0.03 to 0.05, 5.6 to 8.2 radii from the nearest sphere (spots of
/// 15 to 20), the lobe at a quarter took 1.16x to 1.46x the time of no
/// lobe, and connections 1.44x to 1.68x. The spheres of
/// `scenes/` reach 11.4 (the twelve spheres' large light) but for the
/// light between the spheres (61), which takes no connections.
pub const SPHERE_HOT_SPOT: f32 = 12.0;

/// The smallest hot spot of the hottest wall ([`hottest_wall_spot`]) at
/// which the connections pay beside a hot sphere ([`SPHERE_HOT_SPOT`]).
/// Measured as [`SPHERE_HOT_SPOT`]: beside spheres of 35 to 79, walls of
/// 25 to 292 took the connections with the lobe at a quarter in 0.89x to
/// 0.99x the time of the lobe alone, against 1.10x to 1.48x beside walls
/// of 2.1 to 12.8. (Around lights that look large, the same bound once
/// gave the lobe a quarter; the pilot decides there now, [`glow_pilot`].)
pub const WALL_HOT_SPOT: f32 = 15.0;

/// The smallest share of the light's directions that must meet a wall
/// first ([`wall_share`]) for connections to take the glow lobe's place. A
/// connection picks its wall point along a direction from the light's
/// centre, uniform over the sphere: a direction that meets a sphere first
/// or leaves the room through its open side costs the connection's work
/// and finds nothing, and the light those spheres catch is the glow the
/// connections cannot reach. The suite's small lights have shares of
/// 0.83 to 0.93 and took connections in 0.66x to 0.93x the glow lobe's
/// time to relMSE 1e-3 on lavapipe; the low light beside the spheres, near
/// the open side, has 0.65 (0.09 to the spheres, 0.26 out of the room),
/// and connections took 1.09x to 1.16x its time on lavapipe in three runs
/// and 1.06x on the CPU. The held-out light of radius 0.1 at mid height
/// near the open front has 0.70: connections tied with the lobe-less rule
/// there (1.01x) until the light edge's control variate (`FLAG_LIGHT_EDGE`)
/// took the noise of the light's silhouette out of both, which had been a
/// quarter of the error left with connections; then they took 0.87x its
/// time on lavapipe and 0.92x on the CPU (3 seeds, confirmed on 3 more).
/// The bound sits between 0.70 and the held-out light between the spheres
/// (0.675), which was not measured with connections. It holds only where
/// the spheres catch a good share of the rest
/// ([`CONNECT_MAX_SPHERE_SHARE`]).
pub const CONNECT_MIN_WALL_SHARE: f32 = 0.69;

/// The smallest hot spot of the hottest wall ([`hottest_wall_spot`]) at
/// which connections take the glow lobe's place around a small light.
/// Connections pick wall points by the light's directions, which pays
/// where the light makes some wall far brighter than the rest; where it
/// lights every wall about evenly, from the middle of the room, they cost
/// their rays and find little that the BSDF rays miss. Measured with
/// `examples/strategy_probe.rs` (CPU, 128x128, 64 or 256 spp, 4 to 8
/// seeds) on 58 rooms whose small light took connections by the rules
/// here (the scenes of `scenes/` and rooms of `scripts/random_rooms.py`):
/// around the three whose hottest wall had a spot of
/// 1.8 to 2.5 (lights of radius 0.03 to 0.1, 5 to 23 radii from every
/// surface), the fastest choice with connections took 1.11x to 1.46x the
/// time of the fastest without; from a spot of 4.4 up (the held-out light
/// at the front at mid height, 0.92x), connections took 0.36x to 1.01x on
/// all but four (1.06x to 1.35x, at spots of 5.5 to 64). The bound sits
/// between 2.5 and 4.4, geometrically. It changes one scene of `scenes/`,
/// set after it: random room01 (a light of radius 0.076 at a spot of
/// 2.7, 8.6 radii from every surface) takes neither connections nor the
/// lobe, and with connections it took 1.21x that time on the CPU and
/// 1.07x on lavapipe (64 spp, 8 seeds).
pub const CONNECT_MIN_WALL_SPOT: f32 = 3.3;

/// The share of the light's directions that meet a sphere first
/// ([`sphere_share`]) from which a wall share below
/// [`CONNECT_MIN_WALL_SHARE`] keeps a small light from connections. Below
/// it, the directions that miss the walls leave by the room's open side,
/// and the connections still reach the walls the light shines on:
/// measured as [`SPHERE_HOT_SPOT`], two small lights near the open front
/// with wall shares of 0.64 and 0.66 and sphere shares of 0.005 and 0.033
/// took connections in 0.57x and 0.61x the time of the glow-lobe rule (no
/// lobe, the lobe at a quarter), while seven lights of wall shares 0.56
/// to 0.68 whose spheres take 0.087 to 0.21 were fastest without them (the
/// suite's low light beside the spheres, 0.65 and 0.090, took connections
/// in 1.07x its time on the CPU). An eighth, beside a hot sphere and a
/// hot wall, takes them by that rule ([`SPHERE_HOT_SPOT`]): 0.85x the
/// time of the lobe alone.
pub const CONNECT_MAX_SPHERE_SHARE: f32 = 0.06;

/// The largest gap, in light radii, between a small light whose wall
/// share keeps it from connections ([`CONNECT_MIN_WALL_SHARE`]) and the
/// nearest wall or sphere at which it keeps the glow lobe at a quarter;
/// farther out it takes none (spheres counted: a small light's glow is
/// on whatever surface is near it). Set
/// after the held-out scenes' run, on three lights: around the light of
/// radius 0.1 at mid height near the open front (5.0 radii from the
/// ceiling) the lobe took 1.12x the time to relMSE 1e-3 of no lobe on
/// lavapipe and 1.26x on the CPU; the low light beside the spheres (2.4
/// radii from the large one) tied without it, and the light between the
/// spheres (1.0 radius) did not reach the target without it. The bound
/// sits between 2.4 and 5.0. It is not in `glow_rule`, which also gives
/// the connected lights their base flags: there it would change the tiny
/// light's (14 radii from the ceiling), which was not measured without the
/// lobe's share bit. The light near the open front has since taken
/// connections ([`CONNECT_MIN_WALL_SHARE`]): the bound now decides for
/// small lights of a lower wall share, and for those beside a hot sphere
/// that take no connections ([`SPHERE_HOT_SPOT`]).
pub const SMALL_OPEN_CLEARANCE: f32 = 3.5;

/// The gap between the light and the nearest wall or sphere, in light
/// radii (0 where it touches or crosses one).
pub fn surface_clearance(scene: &Scene) -> f32 {
    let light = scene.light;
    let spheres = scene
        .spheres
        .iter()
        .map(|s| ((s.sphere.center - light.center).length() - s.sphere.radius - light.radius).max(0.0) / light.radius);
    wall_clearances(scene).chain(spheres).fold(f32::INFINITY, f32::min)
}

/// Directions from the light's centre for [`wall_share`].
const SHARE_DIRECTIONS: u32 = 4096;

/// Sample points per wall edge and per sphere for [`light_extent`].
const GRID: u32 = 16;

/// How large the light looks from the room: the mean over the walls' and
/// spheres' surfaces (sampled on fixed grids of equal weight per point) of
/// `1 - cos` of the light's half angle, 1 where a point is on or inside the
/// light. 0 for a scene with no surfaces.
pub fn light_extent(scene: &Scene) -> f32 {
    let light = scene.light;
    let extent = |p: Vec3| {
        let cone = light_cone(&light, p);
        if cone.is_empty() { 1.0 } else { cone.one_minus_cos_max as f64 }
    };
    let (mut sum, mut n) = (0.0f64, 0u32);
    let cell = |i: u32| (i as f32 + 0.5) / GRID as f32;
    for w in &scene.walls {
        let w = &w.wall;
        for i in 0..GRID {
            for j in 0..GRID {
                sum += extent(w.corner + cell(i) * w.edge_u + cell(j) * w.edge_v);
                n += 1;
            }
        }
    }
    for s in &scene.spheres {
        let s = &s.sphere;
        // Points equally spaced in z and in azimuth: equal areas.
        for i in 0..GRID {
            let z = 2.0 * cell(i) - 1.0;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..GRID {
                let phi = std::f32::consts::TAU * cell(j);
                sum += extent(s.center + s.radius * Vec3::new(r * phi.cos(), r * phi.sin(), z));
                n += 1;
            }
        }
    }
    if n == 0 { 0.0 } else { (sum / n as f64) as f32 }
}

/// How many walls the light makes hot ([`CORNER_MIN_HOT_SPOT`]): 2 or
/// more for a light in a corner or against an edge.
pub fn hot_walls(scene: &Scene) -> usize {
    hot_spots(scene).filter(|&h| h >= CORNER_MIN_HOT_SPOT).count()
}

/// The [`CORNER_WALLS`]-th largest of [`hot_spots`] (0 with fewer walls):
/// how hot the coolest of a corner's hottest walls is. The light makes a
/// corner or an edge where it is at least [`CORNER_MIN_HOT_SPOT`] (as
/// many as [`CORNER_WALLS`] hot walls, [`hot_walls`]), and one that takes
/// the glow lobe at a quarter where it is at least
/// [`CORNER_QUARTER_HOT_SPOT`].
pub fn corner_hot_spot(scene: &Scene) -> f32 {
    let mut spots: Vec<f32> = hot_spots(scene).collect();
    spots.sort_by(|a, b| b.total_cmp(a));
    spots.get(CORNER_WALLS - 1).copied().unwrap_or(0.0)
}

/// Per wall, how brightly the light lights the wall's nearest point
/// against the walls' mean: `A / (4 pi d^2)`, `A` the walls' total area
/// and `d` the distance from the light's centre to that point. That is the
/// irradiance there of a point source of the light's power facing it,
/// `P / (4 pi d^2)`, over `P / A`, the mean irradiance of walls that share
/// the power evenly; the power cancels. Infinite where the centre is on a
/// wall.
pub fn hot_spots(scene: &Scene) -> impl Iterator<Item = f32> + '_ {
    let c = scene.light.center;
    let area = walls_area(scene);
    scene.walls.iter().map(move |w| spot(area, (nearest_on_wall(&w.wall, c) - c).length_squared()))
}

/// The largest of [`hot_spots`] (0 without walls): how hot the light
/// makes the wall nearest to it.
pub fn hottest_wall_spot(scene: &Scene) -> f32 {
    hot_spots(scene).fold(0.0, f32::max)
}

/// The walls' total area, `A` of [`hot_spots`].
fn walls_area(scene: &Scene) -> f32 {
    scene.walls.iter().map(|w| w.wall.area()).sum()
}

/// A hot spot at squared distance `d2` from the light's centre, for walls
/// of total area `area`: `A / (4 pi d^2)` ([`hot_spots`]).
fn spot(area: f32, d2: f32) -> f32 {
    area / (4.0 * std::f32::consts::PI * d2)
}

/// The hottest sphere's spot, as [`hot_spots`] measures a wall's (the
/// walls' area over `4 pi d^2`, `d` the distance from the light's centre
/// to the sphere's nearest point; infinite where the light's centre is on
/// or in a sphere, 0 without spheres). The connections pick wall points
/// only, and a sphere's side right beside a light is a bright patch they
/// cannot reach, while the glow lobe's directions around the light find
/// it: from [`SPHERE_HOT_SPOT`] the lobe takes a quarter of the BSDF
/// samples, beside the connections where a wall is hot too
/// ([`WALL_HOT_SPOT`]), else in their place.
pub fn sphere_hot_spot(scene: &Scene) -> f32 {
    let c = scene.light.center;
    let area = walls_area(scene);
    let gaps = scene.spheres.iter().map(|s| ((s.sphere.center - c).length() - s.sphere.radius).max(0.0));
    gaps.map(|gap| spot(area, gap * gap)).fold(0.0, f32::max)
}

/// The gap between the light's surface and the nearest point of each
/// wall, in light radii (0 where the light touches or crosses it).
fn wall_clearances(scene: &Scene) -> impl Iterator<Item = f32> + '_ {
    let light = scene.light;
    let c = light.center;
    scene.walls.iter().map(move |w| ((nearest_on_wall(&w.wall, c) - c).length() - light.radius).max(0.0) / light.radius)
}

/// The point of parallelogram `wall` nearest to `p`: its projection onto
/// the plane where that falls inside, else the nearest point of its edges.
fn nearest_on_wall(wall: &pt_core::Wall, p: Vec3) -> Vec3 {
    let (o, u, v) = (wall.corner, wall.edge_u, wall.edge_v);
    // Solve p - o = a u + b v + t n for (a, b) with the Gram matrix of u, v.
    let d = p - o;
    let (uu, uv, vv, du, dv) = (u.dot(u), u.dot(v), v.dot(v), d.dot(u), d.dot(v));
    let det = uu * vv - uv * uv;
    if det > 0.0 {
        let a = (du * vv - dv * uv) / det;
        let b = (dv * uu - du * uv) / det;
        if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
            return o + a * u + b * v;
        }
    }
    let on_segment = |s: Vec3, e: Vec3| {
        let t = if e.length_squared() > 0.0 { ((p - s).dot(e) / e.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        s + t * e
    };
    [on_segment(o, u), on_segment(o, v), on_segment(o + u, v), on_segment(o + v, u)]
        .into_iter()
        .min_by(|x, y| (*x - p).length_squared().total_cmp(&(*y - p).length_squared()))
        .unwrap_or(o)
}

/// Whether the glow lobe pays at its full probability on `scene`: a light
/// that looks small from the room ([`GLOW_MAX_EXTENT`]) in a room of
/// middling albedo ([`GLOW_MAX_ALBEDO`]).
pub fn glow_pays(scene: &Scene) -> bool {
    glow_pays_at(scene, light_extent(scene))
}

/// [`glow_pays`] for a light of extent `extent` ([`light_extent`]).
fn glow_pays_at(scene: &Scene, extent: f32) -> bool {
    extent <= GLOW_MAX_EXTENT && mean_albedo(scene) <= GLOW_MAX_ALBEDO
}

/// The share of the directions from the light's centre, uniform over the
/// sphere, that meet a wall before any sphere (a fixed Fibonacci set of
/// [`SHARE_DIRECTIONS`] directions): where a connection's direction finds
/// its wall point (docs/ARCHITECTURE.md, "Per-scene defaults").
pub fn wall_share(scene: &Scene) -> f32 {
    first_met_share(scene, HitKind::Wall)
}

/// The share of the same directions as [`wall_share`] that meet a sphere
/// first: the light the spheres catch before any wall, which the
/// connections cannot reach. The rest of the directions leave the room
/// through its open side.
pub fn sphere_share(scene: &Scene) -> f32 {
    first_met_share(scene, HitKind::Sphere)
}

/// The share of [`SHARE_DIRECTIONS`] directions from the light's centre
/// whose first surface is of `kind`.
fn first_met_share(scene: &Scene, kind: HitKind) -> f32 {
    let origin = scene.light.center;
    let n = SHARE_DIRECTIONS;
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    let met = (0..n)
        .filter(|&i| {
            let cos = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let phi = golden * i as f32;
            let ray = Ray { origin, dir: Vec3::new(sin * phi.cos(), cos, sin * phi.sin()) };
            first_surface(scene, &ray).kind == kind
        })
        .count();
    met as f32 / n as f32
}

/// The area-weighted mean albedo (mean of the three channels) of the
/// walls and spheres; 0 for a scene with no surfaces.
pub fn mean_albedo(scene: &Scene) -> f32 {
    let mean = |a: Vec3| (a.x + a.y + a.z) / 3.0;
    let walls = scene.walls.iter().map(|w| (w.wall.area(), mean(w.wall.albedo)));
    let spheres =
        scene.spheres.iter().map(|s| (4.0 * std::f32::consts::PI * s.sphere.radius.powi(2), mean(s.sphere.albedo)));
    let (area, weighted) =
        walls.chain(spheres).fold((0.0f64, 0.0f64), |(a, w), (da, al)| (a + da as f64, w + (da * al) as f64));
    if area > 0.0 { (weighted / area) as f32 } else { 0.0 }
}

/// The integrator flags `scene` renders with unless told otherwise, on
/// every backend: the glow-lobe rule ([`glow_flags`]), with connections
/// instead of the glow lobe where they apply ([`connections_apply`]), the
/// light looks small from the room (extent at most [`GLOW_MAX_EXTENT`])
/// and most of its directions meet a wall first ([`wall_share`] at least
/// [`CONNECT_MIN_WALL_SHARE`]); a small light whose share falls short
/// keeps the glow lobe only near a wall or sphere ([`SMALL_OPEN_CLEARANCE`]).
/// With connections every draw comes from the Sobol
/// sequence (`FLAG_SOBOL_DEEP`), and a light in a corner or against an
/// edge ([`hot_walls`]) keeps the glow lobe beside them, at a tenth
/// unless its walls are very hot ([`CORNER_QUARTER_HOT_SPOT`]). A light
/// beside a hot sphere ([`SPHERE_HOT_SPOT`]) takes the glow lobe at a
/// quarter, without connections unless a wall is hot too
/// ([`WALL_HOT_SPOT`]). A light that looks large takes the pilot's
/// choice ([`glow_pilot`]). The glow lobe's share bit
/// (`FLAG_GLOW_SPARSE`) stays as the rule sets it, so that switching the
/// lobe back on gives the share the light calls for.
pub fn default_flags(scene: &Scene) -> u32 {
    with_the_scenes_edge(scene, sampling_rule(scene))
}

/// `flags` without the light edge's control variate where something
/// hides the light's silhouette from the camera ([`silhouette_in_view`]).
fn with_the_scenes_edge(scene: &Scene, flags: u32) -> u32 {
    if silhouette_in_view(scene) { flags } else { flags & !FLAG_LIGHT_EDGE }
}

/// Azimuths per ring of [`silhouette_in_view`].
const SILHOUETTE_AZIMUTHS: u32 = 256;

/// Whether the camera sees the rim of the light's image with nothing in
/// front of it: rays from the camera at 0.8, 0.95 and 0.995 of the light's
/// angular radius from its centre, 256 about it on each ring, meet the
/// light before any wall or sphere. The light edge's control variate
/// (`FLAG_LIGHT_EDGE`) counts the light's share of each pixel its
/// silhouette crosses; where a sphere or a wall hides that part of the
/// silhouette, the pixel shows the nearer surface, and the control variate
/// adds a step as high as the light's radiance to it that was not there:
/// on a probe scene whose large sphere hides part of the light's rim
/// (scenes/probe/low-medium.toml) the default took 1.20x the time without
/// it on lavapipe and 1.13x on the CPU. False where the camera is inside
/// the light.
pub fn silhouette_in_view(scene: &Scene) -> bool {
    let light = scene.light;
    let origin = scene.camera.position;
    let to_center = light.center - origin;
    let d2 = to_center.dot(to_center);
    if d2 <= light.radius * light.radius {
        return false;
    }
    let dist = d2.sqrt();
    let (axis, angle) = (to_center / dist, (light.radius / dist).asin());
    [0.8f32, 0.95, 0.995].iter().all(|&f| {
        let (sin, cos) = (f * angle).sin_cos();
        (0..SILHOUETTE_AZIMUTHS).all(|k| {
            let dir = pt_core::sampling::about_axis(axis, cos, sin, k as f32 / SILHOUETTE_AZIMUTHS as f32);
            let ray = Ray { origin, dir };
            let to_light = pt_core::sphere::intersect_sphere(light.center, light.radius, &ray, 0.0, f32::INFINITY);
            to_light < first_surface(scene, &ray).t
        })
    })
}

/// The first wall or sphere of `scene` that `ray` meets (the light aside).
fn first_surface(scene: &Scene, ray: &Ray) -> Hit {
    let mut hit = Hit::none(f32::INFINITY);
    for (i, w) in scene.walls.iter().enumerate() {
        hit.test_wall(i as u32, &w.wall, ray);
    }
    for (i, sp) in scene.spheres.iter().enumerate() {
        hit.test_sphere(i as u32, &sp.sphere, ray);
    }
    hit
}

/// [`default_flags`] before the light edge's control variate is left out
/// where something hides the light's silhouette.
fn sampling_rule(scene: &Scene) -> u32 {
    // The extent, a cone per grid point (1,792 in the default scene),
    // decides both rules here: worked out once.
    let extent = light_extent(scene);
    let glow = glow_rule(scene, extent);
    // Where walls can shadow the light, or it looks large: the glow-lobe
    // rule, without connections.
    if !connections_apply(scene) || extent > GLOW_MAX_EXTENT {
        return glow;
    }
    let (wall, sphere) = (hottest_wall_spot(scene), sphere_hot_spot(scene));
    let sphere_hot = sphere >= SPHERE_HOT_SPOT;
    // Beside a hot sphere the walls decide: connections where one is hot
    // too. Elsewhere connections need a wall that the light makes hotter
    // than the rest, and a low wall share keeps them off where the spheres
    // catch the light the walls miss, not where it leaves by the open side.
    let without_connections = if sphere_hot {
        wall < WALL_HOT_SPOT
    } else {
        wall < CONNECT_MIN_WALL_SPOT
            || wall_share(scene) < CONNECT_MIN_WALL_SHARE && sphere_share(scene) >= CONNECT_MAX_SPHERE_SHARE
    };
    if without_connections {
        // A small light keeps the glow lobe only near a wall or a sphere.
        return if surface_clearance(scene) > SMALL_OPEN_CLEARANCE { in_the_open() } else { glow };
    }
    let connected = with_connections(glow) | FLAG_SOBOL_DEEP;
    let corner = corner_hot_spot(scene);
    if corner >= CORNER_QUARTER_HOT_SPOT || sphere_hot {
        at_a_quarter(connected)
    } else if corner < CORNER_MIN_HOT_SPOT {
        connected
    } else {
        connected | FLAG_GLOW | FLAG_GLOW_SPARSE
    }
}

/// `flags` with the glow lobe on at a quarter of the BSDF samples.
fn at_a_quarter(flags: u32) -> u32 {
    (flags & !FLAG_GLOW_SPARSE) | FLAG_GLOW
}

/// Integrator `flags` without the bits that change no sample: two flag
/// sets with equal `sample_flags` render the same samples bit for bit.
/// The glow lobe's share (`FLAG_GLOW_SPARSE`) means nothing without the
/// lobe; and where NEE takes the control variate
/// ([`pt_core::integrator::nee_control`]), NEE takes all of the light at
/// every vertex whose light cone is not empty, so a BSDF ray that reaches
/// the light weighs 0 with `FLAG_MIS` or without, and a vertex whose cone
/// is empty has no NEE sample to weigh (its BSDF ray takes the whole light
/// either way).
pub fn sample_flags(flags: u32) -> u32 {
    let mut f = flags;
    if f & FLAG_GLOW == 0 {
        f &= !FLAG_GLOW_SPARSE;
    }
    if pt_core::integrator::nee_control(f) {
        f &= !FLAG_MIS;
    }
    f
}

/// `flags` with connections in the glow lobe's place.
pub fn with_connections(flags: u32) -> u32 {
    (flags & !FLAG_GLOW) | FLAG_CONNECT
}

/// Whether the connections (`FLAG_CONNECT`) are on in `scene`'s kernel:
/// it has walls, and none of them can shadow the light
/// (`pt_core::Wall::cannot_shadow`), so that every wall point is the first
/// one met from the light's centre in its direction, the condition the
/// connections' density rests on. The path loop checks the same (an empty
/// `ShadowWalls`) and leaves them off elsewhere, whatever the flags say.
pub fn connections_apply(scene: &Scene) -> bool {
    match scene.geometry() {
        Ok(g) => !scene.walls.is_empty() && g.walls[..scene.walls.len()].iter().all(|w| w.cannot_shadow(&scene.light)),
        Err(_) => false,
    }
}

/// The glow-lobe rule: [`BASE_FLAGS`] where the glow lobe pays at its full
/// probability ([`glow_pays`]); elsewhere the pilot's choice
/// ([`pilot_choice`]).
pub fn glow_flags(scene: &Scene) -> u32 {
    glow_rule(scene, light_extent(scene))
}

/// [`glow_flags`] for a light of extent `extent` ([`light_extent`]).
fn glow_rule(scene: &Scene, extent: f32) -> u32 {
    if glow_pays_at(scene, extent) { BASE_FLAGS } else { pilot_choice(scene) }
}

/// The relMSE per sample of the three glow-lobe choices on a scene, as
/// [`glow_pilot`] measures them.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GlowPilot {
    /// The glow lobe off.
    pub none: f64,
    /// The lobe at a tenth of the BSDF samples (`FLAG_GLOW_SPARSE`).
    pub tenth: f64,
    /// The lobe at a quarter.
    pub quarter: f64,
}

impl GlowPilot {
    /// The flags it picks: the lobe at the share that leaves less noise (a
    /// quarter where its relMSE per sample is at most
    /// [`PILOT_QUARTER_RATIO`] of a tenth's), where that share's is at most
    /// [`PILOT_LOBE_RATIO`] of no lobe's; else no lobe, with the better
    /// share's bit kept, so that switching the lobe back on gives it.
    pub fn choice(&self) -> u32 {
        let quarter = self.quarter <= PILOT_QUARTER_RATIO * self.tenth;
        let (share, lobe) = if quarter { (BASE_FLAGS, self.quarter) } else { (sparse(), self.tenth) };
        if lobe <= PILOT_LOBE_RATIO * self.none { share } else { share & !FLAG_GLOW }
    }
}

/// The pilot's choices by scene (its TOML, which holds every field):
/// [`default_flags`] is asked for often (every bench curve, every render
/// command), and the pilot takes a fraction of a second.
static PILOT_CHOICES: LazyLock<Mutex<HashMap<String, u32>>> = LazyLock::new(|| Mutex::new(HashMap::new()));

/// [`GlowPilot::choice`] on `scene`, worked out once per scene in a
/// process. Where the CPU renderer cannot take the scene (more walls or
/// spheres than a kernel holds, which a loaded scene never has), the lobe
/// at a tenth, the choice of most large lights measured.
fn pilot_choice(scene: &Scene) -> u32 {
    let key = scene.to_toml();
    let cached = PILOT_CHOICES.lock().unwrap_or_else(|e| e.into_inner()).get(&key).copied();
    if let Some(flags) = cached {
        return flags;
    }
    let flags = glow_pilot(scene).map_or(sparse(), |p| p.choice());
    PILOT_CHOICES.lock().unwrap_or_else(|e| e.into_inner()).insert(key, flags);
    flags
}

/// Measures the glow lobe's choices on `scene`: [`PILOT_RENDERS`] renders
/// each of the lobe off, at a tenth and at a quarter, on the CPU, at
/// [`PILOT_SIDE`] pixels along the longer side and [`PILOT_SPP`] samples
/// per pixel, with the scene's own camera, bounces and light edge
/// ([`silhouette_in_view`]). Per pixel and channel, the variance of one
/// choice's renders over the square of the mean of all of them (plus
/// `metrics::REL_EPSILON`, as `metrics::rel_mse`), times the samples per
/// render, averaged over the image: each choice's relMSE per sample
/// against an estimate of the image that all of them share. It depends on
/// the scene alone: the seeds are fixed, and the CPU renders the same
/// samples on every machine (eight lanes or one). `None` where the CPU
/// renderer cannot take the scene.
pub fn glow_pilot(scene: &Scene) -> Option<GlowPilot> {
    let base = with_the_scenes_edge(scene, BASE_FLAGS);
    let rel = pilot_relmse(scene, &[base & !FLAG_GLOW, base | FLAG_GLOW_SPARSE, base])?;
    Some(GlowPilot { none: rel[0], tenth: rel[1], quarter: rel[2] })
}

/// The pilot's measurement ([`glow_pilot`]) of each of `choices`: its
/// relMSE per sample, against the mean of all of their renders. `None`
/// where the CPU renderer cannot take the scene.
pub fn pilot_relmse(scene: &Scene, choices: &[u32]) -> Option<Vec<f64>> {
    let (width, height) = (scene.render.width.max(1), scene.render.height.max(1));
    let scale = PILOT_SIDE as f32 / width.max(height) as f32;
    let side = |n: u32| ((n as f32 * scale).round() as u32).max(1);
    let settings = RenderSettings { width: side(width), height: side(height), spp: PILOT_SPP, ..scene.render };
    let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
    let values = (settings.width * settings.height * 3) as usize;
    // Per choice, the sum and the sum of squares of each pixel's channels
    // over its renders.
    let mut sums = vec![(vec![0.0f64; values], vec![0.0f64; values]); choices.len()];
    for (flags, (sum, squares)) in choices.iter().zip(&mut sums) {
        for k in 0..PILOT_RENDERS {
            let params = scene.frame_params_with_flags(&settings, PILOT_SPP, PILOT_SEED + k, *flags);
            let mut r = CpuRenderer::new(params, &walls, &spheres).ok()?;
            r.render_frame(PILOT_SPP);
            let image = r.accum().iter().flat_map(|p| p.mean().to_array());
            for ((v, s), q) in image.zip(sum.iter_mut()).zip(squares.iter_mut()) {
                *s += v as f64;
                *q += v as f64 * v as f64;
            }
        }
    }
    let n = PILOT_RENDERS as f64;
    let mut rel = vec![0.0f64; choices.len()];
    for i in 0..values {
        let mean = sums.iter().map(|(s, _)| s[i]).sum::<f64>() / (n * choices.len() as f64);
        let scale = PILOT_SPP as f64 / (mean * mean + crate::metrics::REL_EPSILON) / values as f64;
        for (r, (s, q)) in rel.iter_mut().zip(&sums) {
            let variance = ((q[i] - s[i] * s[i] / n) / (n - 1.0)).max(0.0);
            *r += variance * scale;
        }
    }
    Some(rel)
}

/// The flags where the glow lobe does not pay at its full probability.
///
/// No MIS: with NEE's control variate (in [`BASE_FLAGS`]) NEE takes all of
/// the light. When MIS was dropped the control variate covered only the
/// cones wholly above the horizon, and MIS weighed only the rest; on the
/// scenes that took MIS before the control variate
/// (the large lights, the lights in the open, the bright room; CPU, 64
/// spp, 4 to 6 seeds) relMSE without it was within 0.7% (within 0.2% on
/// most), and lavapipe's frames were about 3% shorter.
fn sparse() -> u32 {
    BASE_FLAGS | FLAG_GLOW_SPARSE
}

/// [`sparse`] without the glow lobe: for a large light far from every
/// wall. Switching `FLAG_GLOW` back on gives [`sparse`].
fn in_the_open() -> u32 {
    sparse() & !FLAG_GLOW
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn with_light(radius: f32, center: Vec3) -> Scene {
        let mut s = Scene::default_scene();
        s.light.radius = radius;
        s.light.center = center;
        s
    }

    #[test]
    fn the_extent_of_a_light_seen_from_one_wall_point_is_its_cones() {
        // Over a 2x2 wall 1 unit below a light of radius 0.1 at its centre,
        // the mean lies between the cone at the centre (the largest, d^2 =
        // 1) and at a corner (the smallest, d^2 = 3).
        let text = "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov_degrees = 40.0\n\
                    [light]\ncenter = [0.0, 1.0, 0.0]\nradius = 0.1\nradiance = [1.0, 1.0, 1.0]\n\
                    [[walls]]\ncorner = [-1.0, 0.0, 1.0]\nedge_u = [2.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, -2.0]\n\
                    albedo = [0.5, 0.5, 0.5]\n";
        let scene = Scene::from_toml(text, Path::new("t.toml")).unwrap();
        let e = light_extent(&scene);
        let at = |d2: f32| {
            let s2 = 0.01 / d2;
            s2 / (1.0 + (1.0 - s2).sqrt())
        };
        assert!(e < at(1.0) && e > at(3.0), "{e}");
        // Without surfaces there is nothing to light: 0.
        let bare = Scene { walls: Vec::new(), spheres: Vec::new(), ..scene };
        assert_eq!(light_extent(&bare), 0.0);
    }

    #[test]
    fn large_lights_take_the_glow_lobe_where_the_pilot_finds_it_pays() {
        let default = Scene::default_scene();
        assert!(light_extent(&default) < GLOW_MAX_EXTENT);
        assert_eq!(glow_flags(&default), BASE_FLAGS);
        // Radius 0.3 half a radius below the ceiling (extent 0.032): the
        // ceiling's glow beside it; the lobe cuts the noise per sample by a
        // quarter, at a tenth or a quarter alike.
        let medium = with_light(0.3, Vec3::new(0.0, 1.55, 0.0));
        assert!(light_extent(&medium) > 2.0 * GLOW_MAX_EXTENT);
        let p = glow_pilot(&medium).unwrap();
        assert!(p.tenth < 0.8 * p.none && p.quarter < 0.8 * p.none, "{p:?}");
        assert_ne!(glow_flags(&medium) & FLAG_GLOW, 0);
        // Radius 0.25 in the middle of the room (0.028), three radii from
        // the walls: nothing bright beside it, and the lobe only costs.
        let centre = with_light(0.25, Vec3::new(0.0, 1.0, 0.0));
        assert!(light_extent(&centre) > GLOW_MAX_EXTENT);
        let p = glow_pilot(&centre).unwrap();
        assert!(p.tenth > 0.96 * p.none && p.quarter > p.none, "{p:?}");
        assert_eq!(glow_flags(&centre), in_the_open());
        assert_eq!(default_flags(&centre), in_the_open());
        // Radius 0.2, 0.22 below the ceiling (extent 0.016): a quarter
        // leaves a quarter less noise than a tenth.
        let near = with_light(0.2, Vec3::new(-0.45, 1.78, -0.3));
        let p = glow_pilot(&near).unwrap();
        assert!(p.quarter < 0.85 * p.tenth, "{p:?}");
        assert_eq!(default_flags(&near), BASE_FLAGS);
        // And the frame parameters' default.
        assert_eq!(centre.frame_params(&centre.render, 1, 0).flags, in_the_open());
        // The extent grows with the light's radius at a fixed centre.
        let radii = [0.02, 0.05, 0.1, 0.2, 0.3, 0.45];
        let e: Vec<f32> = radii.iter().map(|&r| light_extent(&with_light(r, Vec3::new(0.0, 1.0, 0.0)))).collect();
        assert!(e.windows(2).all(|w| w[0] < w[1]), "{e:?}");
    }

    #[test]
    fn the_pilot_keeps_the_better_share_where_it_pays_for_its_cost() {
        let pilot = |tenth, quarter| GlowPilot { none: 1.0, tenth, quarter }.choice();
        assert_eq!(pilot(0.8, 0.85), sparse());
        assert_eq!(pilot(0.8, 0.7), BASE_FLAGS);
        // The quarter must beat the tenth by its margin.
        assert_eq!(pilot(0.8, PILOT_QUARTER_RATIO * 0.8), BASE_FLAGS);
        assert_eq!(pilot(0.8, 0.78), sparse());
        // At the bound the lobe stays; above it, it goes, with the better
        // share's bit kept.
        assert_eq!(pilot(PILOT_LOBE_RATIO, 1.2), sparse());
        assert_eq!(pilot(0.93, 1.1), in_the_open());
        assert_eq!(pilot(1.0, 0.94), BASE_FLAGS & !FLAG_GLOW);
        assert_eq!(pilot(0.95, 0.94), in_the_open());
        assert_eq!(in_the_open() & FLAG_GLOW, 0);
        assert_eq!(in_the_open() | FLAG_GLOW, sparse());
    }

    /// The pilot's relMSE per sample against that of renders on other
    /// seeds measured against a reference of 2,048 spp at the pilot's size
    /// (its own relMSE about 1% of theirs), around the light of radius 0.3
    /// below the ceiling. Tolerance: 10% on each choice and 0.05 on the
    /// lobe's ratios to no lobe; the two sides' seed-to-seed spread, each
    /// over 8 renders of 64x64 pixels, is about 3% and 0.02.
    #[test]
    fn the_pilot_measures_each_choices_relmse_per_sample() {
        let scene = with_light(0.3, Vec3::new(0.0, 1.55, 0.0));
        let pilot = glow_pilot(&scene).unwrap();
        let settings = RenderSettings { width: PILOT_SIDE, height: PILOT_SIDE, spp: PILOT_SPP, ..scene.render };
        let (walls, spheres) = (scene.gpu_walls(), scene.gpu_spheres());
        let render = |flags: u32, seed: u32, spp: u32| {
            let params = scene.frame_params_with_flags(&settings, spp, seed, flags);
            let mut r = CpuRenderer::new(params, &walls, &spheres).unwrap();
            r.render_frame(spp);
            crate::output::mean_radiance(r.accum())
        };
        let reference = render(sparse(), 77, 2048);
        let measured = |flags: u32| {
            let e: f64 = (0..PILOT_RENDERS)
                .map(|k| crate::metrics::rel_mse(&render(flags, 500 + k, PILOT_SPP), &reference))
                .sum();
            e / PILOT_RENDERS as f64 * PILOT_SPP as f64
        };
        let none = measured(in_the_open());
        let (tenth, quarter) = (measured(sparse()), measured(BASE_FLAGS));
        for (got, want) in [(pilot.none, none), (pilot.tenth, tenth), (pilot.quarter, quarter)] {
            assert!((got / want - 1.0).abs() < 0.1, "pilot {pilot:?}, measured {none} {tenth} {quarter}");
        }
        assert!((pilot.tenth / pilot.none - tenth / none).abs() < 0.05, "{pilot:?} {none} {tenth}");
        assert!((pilot.quarter / pilot.none - quarter / none).abs() < 0.05, "{pilot:?} {none} {quarter}");
    }

    /// The camera sees the light's rim in every scene of the suite, the
    /// held-out set, the probes, the scenes with more spheres and the
    /// contact scenes but three: in the probe whose large sphere stands
    /// before part of it, and in the two contact scenes whose light rises
    /// through the ceiling, the light edge's control variate is off. (The
    /// light tangent to the ceiling keeps it.)
    #[test]
    fn the_light_edge_control_variate_is_off_where_something_hides_the_lights_rim() {
        let scenes = scene_files(&["", "holdout", "probe", "spheres", "contact"]);
        assert_eq!(scenes.len(), 37);
        for (name, scene) in scenes {
            let hidden = ["low-medium", "light-through-ceiling", "light-in-corner-walls"].contains(&name.as_str());
            assert_eq!(silhouette_in_view(&scene), !hidden, "{name}");
            assert_eq!(default_flags(&scene) & FLAG_LIGHT_EDGE == 0, hidden, "{name}");
        }
        // A sphere moved in front of the default light's edge hides it.
        let mut scene = Scene::default_scene();
        assert!(silhouette_in_view(&scene));
        // On the way from the camera to the light's right rim, 1.9 from
        // the camera.
        scene.spheres[1].sphere.center = Vec3::new(0.084, 1.391, 1.5);
        scene.spheres[1].sphere.radius = 0.02;
        assert!(!silhouette_in_view(&scene));
    }

    #[test]
    fn the_suites_scenes_get_the_strategies_the_suite_measured_best() {
        // The glow lobe at a tenth: the bright room, the light of radius
        // 0.3 below the ceiling, and the wide light below the ceiling of
        // scenes/holdout/; none: the large lights in the open, of radius
        // 0.25 in the middle of the room, 0.19 and 0.22 off centre, and
        // the light of radius 0.5, which tied with the tenth it had before
        // the pilot (0.051 s against 0.053 s on lavapipe, 0.054 s against
        // 0.052 s on the CPU); at a quarter, every other scene. The light
        // of radius 0.3 before the back wall of scenes/holdout/ keeps its
        // tenth, which the suite's run measured 1.03x and 1.05x faster
        // than a quarter: the pilot reads the quarter 0.98 of the tenth,
        // within its margin.
        let tenth = ["bright-room", "light-medium", "light-ceiling-wide", "light-wall-medium"];
        let none = ["light-centre", "light-free-small", "light-open-mid", "light-large"];
        let scenes = scene_files(&["", "holdout"]);
        assert_eq!(scenes.len(), 18);
        for (name, scene) in scenes {
            let expected = if tenth.contains(&name.as_str()) {
                sparse()
            } else if none.contains(&name.as_str()) {
                in_the_open()
            } else {
                BASE_FLAGS
            };
            assert_eq!(glow_flags(&scene), expected, "{name}");
        }
    }

    /// The scenes of `scenes/` and of its folders `subs` ("" for itself),
    /// by file name without `.toml`.
    fn scene_files(subs: &[&str]) -> Vec<(String, Scene)> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut scenes = Vec::new();
        for sub in subs {
            for entry in std::fs::read_dir(dir.join(sub)).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "toml") {
                    let name = path.file_stem().unwrap().to_string_lossy().into_owned();
                    scenes.push((name, Scene::load(&path).unwrap()));
                }
            }
        }
        scenes
    }

    /// Connections replace the glow lobe around the small lights wherever
    /// no wall shadows the light (every scene of the suite), beside the
    /// lobe in a corner; large lights keep the glow-lobe rule, and so do a
    /// partition that can stand between the room and the light, a light
    /// outside the room, and a scene without walls.
    #[test]
    fn connections_replace_the_glow_lobe_around_small_lights_in_rooms_that_do_not_shadow_them() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let small = ["bright-room", "default", "light-corner", "light-low", "light-near-wall", "light-small"];
        let held_out = ["light-between-spheres", "light-front-high", "light-front-mid"];
        let small = [small.as_slice(), &["light-tiny", "sphere-in-corner"], &held_out].concat();
        // The low light: a third of its directions meet a sphere or leave
        // the room first; so for the held-out light between the spheres.
        let walled = |name: &str| !["light-low", "light-between-spheres"].contains(&name);
        let scenes = scene_files(&["", "holdout"]);
        assert_eq!(scenes.len(), 18);
        for (name, scene) in scenes {
            assert!(connections_apply(&scene), "{name}");
            let beside = name == "light-corner";
            assert_eq!(hot_walls(&scene) >= CORNER_WALLS, beside, "{name}");
            let is_small = small.contains(&name.as_str());
            assert_eq!(light_extent(&scene) <= GLOW_MAX_EXTENT, is_small, "{name}");
            let glow = glow_flags(&scene);
            let connected = with_connections(glow) | FLAG_SOBOL_DEEP | if beside { FLAG_GLOW } else { 0 };
            if is_small {
                assert_eq!(wall_share(&scene) >= CONNECT_MIN_WALL_SHARE, walled(&name), "{name}");
            }
            let connects = is_small && walled(&name);
            if is_small && !connects {
                // Neither unconnected small light is far from every
                // surface: both keep the glow lobe.
                assert!(surface_clearance(&scene) <= SMALL_OPEN_CLEARANCE, "{name}");
            }
            assert_eq!(default_flags(&scene), if connects { connected } else { glow }, "{name}");
        }
        // The light the open-clearance bound was measured on lies beyond
        // it, now with connections, and a wall share just above their bound.
        let front = Scene::load(&dir.join("holdout/light-front-mid.toml")).unwrap();
        assert!(surface_clearance(&front) > SMALL_OPEN_CLEARANCE);
        assert!((CONNECT_MIN_WALL_SHARE..0.72).contains(&wall_share(&front)), "{}", wall_share(&front));
        let default = Scene::default_scene();
        // The default light: 0.15 below the ceiling, 1 radius.
        assert!((surface_clearance(&default) - 1.0).abs() < 1e-5, "{}", surface_clearance(&default));
        let mut partition = default.clone();
        let v = Vec3::new;
        partition.walls.push(crate::scene::NamedWall {
            name: "partition".into(),
            wall: pt_core::Wall::new(v(-0.6, 0.0, 0.2), v(0.9, 0.0, -0.6), v(0.0, 1.3, 0.0), Vec3::splat(0.5)),
        });
        assert!(!connections_apply(&partition));
        assert_eq!(default_flags(&partition), glow_flags(&partition));
        assert_eq!(default_flags(&partition) & FLAG_CONNECT, 0);
        let outside = with_light(0.1, Vec3::new(0.0, 1.0, -1.5));
        assert!(!connections_apply(&outside));
        let bare = Scene { walls: Vec::new(), ..default.clone() };
        assert!(!connections_apply(&bare));
        assert_eq!(default_flags(&bare), glow_flags(&bare));
        // The default scene's small light: connections.
        assert_eq!(default_flags(&default), with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP);
        // A large light: the pilot's choice, without connections, even in a
        // corner (its centre 0.4 from three walls, all hot), and a light in
        // the open: none.
        let large = with_light(0.5, Vec3::new(0.0, 1.35, 0.0));
        assert_eq!(default_flags(&large), glow_flags(&large));
        let cornered = with_light(0.3, Vec3::new(0.6, 1.6, -0.6));
        assert!(light_extent(&cornered) > GLOW_MAX_EXTENT);
        assert_eq!(hot_walls(&cornered), 3);
        assert_eq!(default_flags(&cornered), glow_flags(&cornered));
        assert_eq!(default_flags(&cornered) & FLAG_CONNECT, 0);
        let open = with_light(0.25, Vec3::new(0.0, 1.0, 0.0));
        assert!(light_extent(&open) > GLOW_MAX_EXTENT);
        assert_eq!(default_flags(&open), in_the_open());
        // The bright room's small light: connections, with the glow rule's
        // tenth share bit.
        let mut bright = default.clone();
        for w in &mut bright.walls {
            w.wall.albedo = Vec3::splat(0.9);
        }
        assert!(!glow_pays(&bright));
        assert_eq!(default_flags(&bright), with_connections(sparse()) | FLAG_SOBOL_DEEP);
    }

    #[test]
    fn the_wall_share_counts_the_directions_that_meet_a_wall_first() {
        // The default room is open at the front: about 0.14 of the
        // directions leave through it and 0.03 meet a sphere.
        let default = Scene::default_scene();
        let share = wall_share(&default);
        assert!((share - 0.834).abs() < 0.01, "{share}");
        // Closed by a sixth wall, without spheres: every direction.
        let mut closed = Scene { spheres: Vec::new(), ..default.clone() };
        let v = Vec3::new;
        closed.walls.push(crate::scene::NamedWall {
            name: "front".into(),
            wall: pt_core::Wall::new(v(1.0, 0.0, 1.0), v(-2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), Vec3::splat(0.5)),
        });
        assert_eq!(wall_share(&closed), 1.0);
        // A sphere around the light hides every wall; without walls
        // nothing is met.
        let mut hidden = closed.clone();
        hidden.spheres.push(crate::scene::NamedSphere {
            name: "shell".into(),
            sphere: pt_core::Sphere::new(hidden.light.center, 0.3, Vec3::splat(0.5)),
        });
        assert_eq!(wall_share(&hidden), 0.0);
        assert_eq!(wall_share(&Scene { walls: Vec::new(), ..default.clone() }), 0.0);
        // Below the bound, a small light keeps the glow-lobe rule.
        let low = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/light-low.toml")).unwrap();
        assert!(light_extent(&low) <= GLOW_MAX_EXTENT);
        assert!(wall_share(&low) < CONNECT_MIN_WALL_SHARE);
        assert_eq!(default_flags(&low), glow_flags(&low));
    }

    #[test]
    fn connections_need_a_wall_the_light_makes_hot() {
        // A light of radius 0.05 in the middle of the room: every wall's
        // nearest point 1 or more away, the hottest a spot of 20 / (4 pi),
        // and the large sphere 8 radii away. Neither connections nor the
        // glow lobe.
        let middle = with_light(0.05, Vec3::new(0.0, 1.0, 0.0));
        let spot = hottest_wall_spot(&middle);
        assert!((spot - 20.0 / (4.0 * std::f32::consts::PI)).abs() < 1e-4, "{spot}");
        assert!(spot < CONNECT_MIN_WALL_SPOT);
        assert!(wall_share(&middle) >= CONNECT_MIN_WALL_SHARE);
        assert!(sphere_hot_spot(&middle) < SPHERE_HOT_SPOT);
        assert!(surface_clearance(&middle) > SMALL_OPEN_CLEARANCE);
        assert_eq!(default_flags(&middle), in_the_open());
        // So for random room01, a light of radius 0.076 at a spot of 2.7.
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/random");
        let room01 = Scene::load(&dir.join("room01.toml")).unwrap();
        assert!((2.6..2.8).contains(&hottest_wall_spot(&room01)), "{}", hottest_wall_spot(&room01));
        assert_eq!(default_flags(&room01), in_the_open());
        // Raised to 0.45 below the ceiling (a spot of 7.9): connections.
        let higher = with_light(0.05, Vec3::new(0.0, 1.55, 0.0));
        assert!(hottest_wall_spot(&higher) > CONNECT_MIN_WALL_SPOT);
        assert_eq!(default_flags(&higher), with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP);
    }

    #[test]
    fn a_low_wall_share_keeps_connections_off_only_where_the_spheres_catch_the_light() {
        // The default room: about 0.03 of the directions meet a sphere.
        let default = Scene::default_scene();
        assert!((sphere_share(&default) - 0.030).abs() < 0.005, "{}", sphere_share(&default));
        // Near the open front, above the spheres, 0.6 below the ceiling (a
        // spot of 4.4): 0.60 meet a wall, 0.03 a sphere; the rest leave the
        // room. Connections.
        let front = with_light(0.05, Vec3::new(0.0, 1.4, 0.7));
        assert!(hottest_wall_spot(&front) > CONNECT_MIN_WALL_SPOT);
        assert!(wall_share(&front) < CONNECT_MIN_WALL_SHARE);
        assert!(sphere_share(&front) < CONNECT_MAX_SPHERE_SHARE);
        assert_eq!(default_flags(&front), with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP);
        // Lower, in front of the large sphere: 0.09 meet a sphere. No
        // connections, and no lobe 8 radii from every surface.
        let low = with_light(0.05, Vec3::new(-0.2, 0.6, 0.5));
        assert!(wall_share(&low) < CONNECT_MIN_WALL_SHARE);
        assert!(sphere_share(&low) >= CONNECT_MAX_SPHERE_SHARE);
        assert!(sphere_hot_spot(&low) < SPHERE_HOT_SPOT);
        assert_eq!(default_flags(&low), in_the_open());
        // Every direction meets a wall or a sphere in a closed room.
        let mut closed = default.clone();
        let v = Vec3::new;
        closed.walls.push(crate::scene::NamedWall {
            name: "front".into(),
            wall: pt_core::Wall::new(v(1.0, 0.0, 1.0), v(-2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), Vec3::splat(0.5)),
        });
        assert_eq!(wall_share(&closed) + sphere_share(&closed), 1.0);
    }

    /// The probe scenes' defaults, as their last run measured them
    /// (docs/bench/probe.md).
    #[test]
    fn the_probe_scenes_get_the_strategies_their_run_measured() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/probe");
        let connected = with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP;
        let quarter = connected | FLAG_GLOW;
        let tenth = quarter | FLAG_GLOW_SPARSE;
        let expected = [
            ("big-sphere", connected),
            ("corner-hot", quarter),
            ("edge-mild", tenth),
            ("edge-small", tenth),
            // Its large sphere hides part of the light's rim.
            ("low-medium", sparse() & !FLAG_LIGHT_EDGE),
            ("mid-large", in_the_open()),
            ("near-large", sparse()),
            ("open-large", in_the_open()),
            ("small-corner", tenth),
            ("wall-small", connected),
        ];
        let count = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(count, expected.len());
        for (name, flags) in expected {
            let scene = Scene::load(&dir.join(format!("{name}.toml"))).unwrap();
            assert_eq!(default_flags(&scene), flags, "{name}");
        }
    }

    #[test]
    fn hot_walls_make_a_corner_or_an_edge() {
        // The default light, its centre 0.3 below the ceiling of a room of
        // five 2x2 walls: the ceiling's hot spot is 20 / (4 pi 0.09), the
        // side walls' (1 away) 20 / (4 pi), the floor's 20 / (4 pi 1.7^2).
        let default = Scene::default_scene();
        let spots: Vec<f32> = hot_spots(&default).collect();
        let at = |d: f32| 20.0 / (4.0 * std::f32::consts::PI * d * d);
        for (got, want) in spots.iter().zip([at(1.7), at(0.3), at(1.0), at(1.0), at(1.0)]) {
            assert!((got - want).abs() < 1e-4 * want, "{spots:?}");
        }
        assert_eq!(hot_walls(&default), 1);
        assert_eq!(default_flags(&default) & FLAG_GLOW, 0);
        // Moved to 0.225 from the right wall too: an edge, and the glow
        // lobe joins the connections, at a tenth: the cooler of the two hot
        // spots, the ceiling's 17.7, is below the quarter's bound.
        let edge = with_light(0.15, Vec3::new(1.0 - 0.225, 1.7, 0.0));
        assert_eq!(hot_walls(&edge), 2);
        assert!((corner_hot_spot(&edge) - 20.0 / (4.0 * std::f32::consts::PI * 0.09)).abs() < 1e-3);
        assert_eq!(default_flags(&edge), BASE_FLAGS | FLAG_GLOW_SPARSE | FLAG_CONNECT | FLAG_SOBOL_DEEP);
        // 0.55 from it (a spot of 5.3): one hot wall again.
        let off = with_light(0.15, Vec3::new(1.0 - 0.55, 1.7, 0.0));
        assert_eq!(hot_walls(&off), 1);
        // Half a radius from the ceiling, the right and the back walls,
        // spots of 49 on each: a quarter.
        let corner = with_light(0.12, Vec3::new(0.82, 1.82, -0.82));
        assert_eq!(hot_walls(&corner), 3);
        assert!(corner_hot_spot(&corner) > CORNER_QUARTER_HOT_SPOT);
        assert_eq!(default_flags(&corner), BASE_FLAGS | FLAG_CONNECT | FLAG_SOBOL_DEEP);
        // The nearest wall's gap is the clearance.
        assert!((surface_clearance(&corner) - 0.5).abs() < 1e-4);
        // A tinier light 0.2 below the ceiling and 0.4 from two walls is
        // 1.86 radii from the nearest: a corner by its hot spots (40, 9.9
        // and 9.9) though not in light radii; at a tenth.
        let tiny = with_light(0.07, Vec3::new(0.6, 1.8, -0.6));
        assert!(surface_clearance(&tiny) > 1.8);
        assert_eq!(hot_walls(&tiny), 3);
        assert_eq!(default_flags(&tiny), BASE_FLAGS | FLAG_GLOW_SPARSE | FLAG_CONNECT | FLAG_SOBOL_DEEP);
        // Without walls there is no second spot.
        assert_eq!(corner_hot_spot(&Scene { walls: Vec::new(), ..default.clone() }), 0.0);
        // Past a wall's edge the nearest point is on the edge: a point 0.5
        // beyond the floor's front edge (z = 1) and level with it.
        let floor = &default.walls[0].wall;
        let p = Vec3::new(0.0, 0.0, 1.5);
        assert!((nearest_on_wall(floor, p) - Vec3::new(0.0, 0.0, 1.0)).length() < 1e-6);
        // Above a wall's inside, the projection onto its plane.
        let p = Vec3::new(0.3, 0.7, -0.2);
        assert!((nearest_on_wall(floor, p) - Vec3::new(0.3, 0.0, -0.2)).length() < 1e-6);
    }

    #[test]
    fn a_sphere_beside_the_light_takes_the_glow_lobe_at_a_quarter_unless_a_wall_is_hotter() {
        // The default spheres: the large one (radius 0.4 at (-0.45, 0.4,
        // -0.3)) is 1.2 from the default light's centre, a spot of 1.6:
        // connections alone.
        let default = Scene::default_scene();
        let nearest = (default.spheres[0].sphere.center - default.light.center).length() - 0.4;
        let at = |d: f32| 20.0 / (4.0 * std::f32::consts::PI * d * d);
        assert!((sphere_hot_spot(&default) - at(nearest)).abs() < 1e-4 * at(nearest));
        assert!((hottest_wall_spot(&default) - at(0.3)).abs() < 1e-4 * at(0.3));
        assert_eq!(default_flags(&default), with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP);
        // A light of radius 0.1 whose centre is 0.3 above the large
        // sphere's top, mid-room: a spot of 17.7, no wall above 5.3 (the
        // left one, 0.55 away): the glow lobe at a quarter, no connections.
        let above = with_light(0.1, Vec3::new(-0.45, 1.1, -0.3));
        assert!((sphere_hot_spot(&above) - at(0.3)).abs() < 1e-3 * at(0.3));
        assert!(sphere_hot_spot(&above) >= SPHERE_HOT_SPOT);
        assert!(hottest_wall_spot(&above) < 5.3);
        assert_eq!(default_flags(&above), BASE_FLAGS);
        // Of radius 0.05 there, 5 radii from the sphere: no lobe either.
        let small = with_light(0.05, Vec3::new(-0.45, 1.1, -0.3));
        assert!(surface_clearance(&small) > SMALL_OPEN_CLEARANCE);
        assert_eq!(default_flags(&small), in_the_open());
        // 0.4 above it, a spot of 9.9: connections alone.
        let higher = with_light(0.1, Vec3::new(-0.45, 1.2, -0.3));
        assert!(sphere_hot_spot(&higher) < SPHERE_HOT_SPOT);
        assert_eq!(default_flags(&higher), with_connections(BASE_FLAGS) | FLAG_SOBOL_DEEP);
        // 0.3 above a sphere pushed against the back wall, 0.25 from it: a
        // hot wall (25) too; the lobe joins the connections at a quarter.
        let mut walled = above.clone();
        walled.spheres[0].sphere.center.z = -0.55;
        walled.light.center.z = -0.75;
        assert!(hottest_wall_spot(&walled) >= WALL_HOT_SPOT);
        assert!(sphere_hot_spot(&walled) >= SPHERE_HOT_SPOT);
        assert_eq!(default_flags(&walled), BASE_FLAGS | FLAG_CONNECT | FLAG_SOBOL_DEEP);
        // Without spheres there is no spot.
        assert_eq!(sphere_hot_spot(&Scene { spheres: Vec::new(), ..default.clone() }), 0.0);
        // A very hot sphere makes the light look large: a light of radius
        // 0.2, its centre 0.22 above the large sphere (a spot of 33),
        // mid-room, takes the pilot's choice, the lobe without
        // connections: its relMSE per sample about 0.6 of no lobe's.
        let large = with_light(0.2, Vec3::new(-0.45, 1.02, -0.3));
        assert!(light_extent(&large) > GLOW_MAX_EXTENT);
        assert!(sphere_hot_spot(&large) >= CORNER_QUARTER_HOT_SPOT);
        assert!(hottest_wall_spot(&large) < WALL_HOT_SPOT);
        assert_eq!(default_flags(&large), glow_flags(&large));
        assert_ne!(default_flags(&large) & FLAG_GLOW, 0);
    }

    #[test]
    fn a_bright_room_takes_the_sparse_glow_lobe_and_mis() {
        let default = Scene::default_scene();
        let a = mean_albedo(&default);
        assert!(a > 0.5 && a < 0.6, "{a}");
        let mut bright = default.clone();
        for w in &mut bright.walls {
            w.wall.albedo = Vec3::splat(0.9);
        }
        for s in &mut bright.spheres {
            s.sphere.albedo = Vec3::splat(0.9);
        }
        assert!((mean_albedo(&bright) - 0.9).abs() < 1e-6);
        assert_eq!(glow_flags(&bright), sparse());
        // Area weights: one 2x2 wall of albedo 1 and one of 0 average 1/2,
        // a sphere of radius 1 (area 4 pi) against a 2x2 wall (area 4)
        // weighs pi times as much.
        let mut two = default.clone();
        two.spheres.clear();
        two.walls.truncate(2);
        two.walls[0].wall.albedo = Vec3::ONE;
        two.walls[1].wall.albedo = Vec3::ZERO;
        assert!((mean_albedo(&two) - 0.5).abs() < 1e-6);
        two.walls.truncate(1);
        two.spheres = default.spheres[..1].to_vec();
        two.spheres[0].sphere.radius = 1.0;
        two.spheres[0].sphere.albedo = Vec3::ZERO;
        let pi = std::f32::consts::PI;
        assert!((mean_albedo(&two) - 1.0 / (1.0 + pi)).abs() < 1e-6);
    }
}
