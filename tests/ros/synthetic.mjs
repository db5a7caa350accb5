// The synthetic recording every fixture holds, whatever its format (README.md in this folder):
// the same formulas are in make_ros1_fixture.py and in tests/ros/import_test.cpp, which checks
// the imported values against them.
export const HAND = ["index_abduction", "index_flex1", "index_flex2", "index_flex3", "middle_abduction", "middle_flex1",
  "middle_flex2", "middle_flex3", "ring_abduction", "ring_flex1", "ring_flex2", "ring_flex3", "thumb_abduction",
  "thumb_flex1", "thumb_flex2", "thumb_flex3"];
export const BASE_SEC = 1700000000;
export const BASE_NSEC = 250000000;
export const JOINT_MESSAGES = 200;  // 200 Hz: stamp k * 5 ms
export const FRAMES = 10;           // 20 Hz: stamp f * 50 ms + 2.5 ms
export const TF_SAMPLES = 101;      // 100 Hz: stamp i * 10 ms
export const TRUTH_SAMPLES = 100;   // 100 Hz: stamp i * 10 ms + 1 ms

// The message order in the joint topic: arm joints first, the hand's in reverse.
export const JOINT_NAMES = ["arm_joint_1", "arm_joint_2", ...HAND.slice().reverse()];
export const q = (j, k) => 0.1 + 0.02 * j + 0.001 * k;        // j: index in HAND
export const effort = (j, k) => 0.01 * j - 0.0005 * k;
// Header stamps of joint message k (ns after the base); 101 and 100 swapped, 51 repeats 50.
export function jointStampNs(k) {
  const kk = k === 100 ? 101 : k === 101 ? 100 : k === 51 ? 50 : k;
  return kk * 5000000;
}
export const frameStampNs = (f) => f * 50000000 + 2500000;
export const tfStampNs = (i) => i * 10000000;
export const truthStampNs = (i) => i * 10000000 + 1000000;
export function pixel(x, y, f) {
  return [(x * 4 + f * 7) & 255, (y * 5 + f) & 255, ((x ^ y) * 3) & 255];
}
export const WIDTH = 64, HEIGHT = 48;
export const K = [60, 0, 31.5, 0, 60, 23.5, 0, 0, 1];
export const D = [0.01, -0.002, 0.0005, 0.0003, 0];

// Poses as [x, y, z], [qx, qy, qz, qw]; s in seconds after the base.
const aboutZ = (a) => [0, 0, Math.sin(a / 2), Math.cos(a / 2)];
const aboutX = (a) => [Math.sin(a / 2), 0, 0, Math.cos(a / 2)];
export const worldPalm = { t: [0.1, 0.2, 0.3], q: aboutZ(Math.PI / 6) };                 // static
export const cameraLinkOptical = { t: [0, 0, 0], q: [-0.5, 0.5, -0.5, 0.5] };          // static
export const worldCameraLink = (s) => ({ t: [0.5 + 0.1 * s, -0.2, 0.4], q: aboutZ(0.2 * s) });
export const worldObject = (s) => ({ t: [0.15, 0.2 + 0.05 * s, 0.35], q: aboutX(0.1 * s) });
// The object seen from camera_link: a fixed offset there (Odometry's frame in the fixtures).
export const cameraLinkObject = (s) => ({ t: [0.05, 0.1 + 0.02 * s, -0.03], q: aboutX(0.3 * s) });
export const tableMarker = { t: [1, 0, 0], q: [0, 0, 0, 1] };                            // a second tree

export function stamp(ns) {
  const total = BigInt(BASE_SEC) * 1000000000n + BigInt(BASE_NSEC) + BigInt(ns);
  return { sec: Number(total / 1000000000n), nanosec: Number(total % 1000000000n), ns: total };
}
