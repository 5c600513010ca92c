//! Camera controls: orbit about the look-at point, zoom toward it, fly.

use pt_core::glam::Vec3;
use pt_render::scene::CameraDesc;

/// Radians of orbit per pixel dragged.
pub const ORBIT_RADIANS_PER_PIXEL: f32 = 0.005;
/// Distance factor per wheel notch (zoom in by 10%).
pub const ZOOM_PER_NOTCH: f32 = 0.9;
/// Flying speed in scene units per second (the default room is 2 wide).
pub const FLY_SPEED: f32 = 1.0;
/// Closest approach of a zoom to the look-at point, in scene units: zoom
/// never reaches or passes the target, and the view direction stays exact.
const MIN_DISTANCE: f32 = 1e-4;
/// Largest elevation angle: the view never flips over the pole.
const MAX_PITCH: f32 = 1.55;

/// Rotates the camera about its look-at point: `yaw` about the world up
/// (+y), `pitch` up or down. The look-at point and the distance stay.
pub fn orbit(cam: &CameraDesc, yaw: f32, pitch: f32) -> CameraDesc {
    let offset = cam.position - cam.look_at;
    let dist = offset.length();
    let dir = offset / dist;
    let cur_pitch = dir.y.clamp(-1.0, 1.0).asin();
    let cur_yaw = dir.x.atan2(dir.z);
    let p = (cur_pitch + pitch).clamp(-MAX_PITCH, MAX_PITCH);
    let y = cur_yaw + yaw;
    let new_dir = Vec3::new(p.cos() * y.sin(), p.sin(), p.cos() * y.cos());
    CameraDesc { position: cam.look_at + new_dir * dist, up: Vec3::Y, ..*cam }
}

/// Moves the camera toward (`notches` > 0) or away from its look-at point
/// by a factor per notch. The direction stays and the look-at point is
/// never reached.
pub fn zoom(cam: &CameraDesc, notches: f32) -> CameraDesc {
    let offset = cam.position - cam.look_at;
    let dist = offset.length();
    let new_dist = (dist * ZOOM_PER_NOTCH.powf(notches)).max(MIN_DISTANCE.min(dist));
    CameraDesc { position: cam.look_at + offset * (new_dist / dist), ..*cam }
}

/// Translates camera and look-at point along the view axes: `forward`
/// along the viewing direction, `right` across it, `up` along world up;
/// each in scene units.
pub fn fly(cam: &CameraDesc, forward: f32, right: f32, up: f32) -> CameraDesc {
    let f = (cam.look_at - cam.position).normalize();
    let r = f.cross(cam.up).normalize();
    let delta = f * forward + r * right + Vec3::Y * up;
    CameraDesc { position: cam.position + delta, look_at: cam.look_at + delta, ..*cam }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pt_render::Scene;

    fn cam() -> CameraDesc {
        Scene::default_scene().camera
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn orbit_keeps_target_and_distance() {
        let c = cam();
        let d = (c.position - c.look_at).length();
        let mut o = c;
        for i in 0..100 {
            o = orbit(&o, 0.37, if i % 2 == 0 { 0.2 } else { -0.15 });
            assert_eq!(o.look_at, c.look_at);
            assert!(((o.position - o.look_at).length() - d).abs() < 1e-4);
        }
        // A quarter turn to the right puts the camera on the +x side.
        let q = orbit(&c, std::f32::consts::FRAC_PI_2, 0.0);
        assert!(close(q.position, c.look_at + Vec3::new(d, 0.0, 0.0)), "{}", q.position);
    }

    #[test]
    fn orbit_never_flips_over_the_pole() {
        let o = orbit(&cam(), 0.0, 10.0);
        let dir = (o.position - o.look_at).normalize();
        assert!(dir.y < 1.0 && dir.y > 0.99);
        // Up is still not parallel to the view: the camera stays valid.
        assert!(dir.cross(o.up).length() > 1e-3);
    }

    #[test]
    fn zoom_never_passes_through_the_target() {
        let c = cam();
        let dir = (c.position - c.look_at).normalize();
        let mut z = c;
        for _ in 0..1000 {
            z = zoom(&z, 5.0);
            let off = z.position - z.look_at;
            assert!(off.length() > 0.0, "reached the target");
            assert!(close(off.normalize(), dir), "passed or turned");
        }
        let out = zoom(&c, -1.0);
        assert!((out.position - out.look_at).length() > (c.position - c.look_at).length());
    }

    #[test]
    fn fly_moves_along_the_view_axes() {
        let c = cam(); // looks toward -z from (0, 1, 3.4)
        let f = fly(&c, 1.0, 0.0, 0.0);
        assert!(close(f.position, c.position + Vec3::new(0.0, 0.0, -1.0)));
        assert!(close(f.look_at - f.position, c.look_at - c.position));
        let r = fly(&c, 0.0, 0.5, 0.0);
        assert!(close(r.position, c.position + Vec3::new(0.5, 0.0, 0.0)));
        let u = fly(&c, 0.0, 0.0, -0.25);
        assert!(close(u.position, c.position + Vec3::new(0.0, -0.25, 0.0)));
    }
}
