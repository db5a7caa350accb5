// Writes the ROS 2 fixtures of the synthetic recording with the official implementations:
// @mcap/core (MCAP: unchunked, zstd- and lz4-chunked), @foxglove/rosmsg2-serialization (CDR),
// sql.js for rosbag2's .db3 tables. Run: node tests/ros/make_fixtures.mjs tests/ros/fixtures
// (after npm ci in tests/ros/node). The outputs are committed; tests read them.
import { writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import * as S from "./synthetic.mjs";
import { Ros2Writer } from "./ros2_writer.mjs";

const require = createRequire(import.meta.url);
const out = process.argv[2] ?? "fixtures";

function header(ns, frame) {
  const s = S.stamp(ns);
  return { stamp: { sec: s.sec, nanosec: s.nanosec }, frame_id: frame };
}
function tf(ns, parent, child, pose) {
  return { header: header(ns, parent), child_frame_id: child,
    transform: { translation: { x: pose.t[0], y: pose.t[1], z: pose.t[2] }, rotation: { x: pose.q[0], y: pose.q[1], z: pose.q[2], w: pose.q[3] } } };
}
function image(f, encoding = "rgb8") {
  const data = new Uint8Array(S.WIDTH * S.HEIGHT * 3);
  for (let y = 0; y < S.HEIGHT; ++y)
    for (let x = 0; x < S.WIDTH; ++x) data.set(S.pixel(x, y, f), (y * S.WIDTH + x) * 3);
  return { header: header(S.frameStampNs(f), "camera_optical"), height: S.HEIGHT, width: S.WIDTH, encoding, is_bigendian: 0, step: S.WIDTH * 3, data };
}
// The synthetic camera's intrinsics, for an image `scale` times its size (a camera of that size).
function cameraInfo(ns, width, height, scale = 1) {
  const k = S.K.map((v, i) => (i < 6 ? v * scale : v));
  return { header: header(ns, "camera_optical"), height, width, distortion_model: "plumb_bob", d: S.D, k,
    r: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: [k[0], 0, k[2], 0, 0, k[4], k[5], 0, 0, 0, 1, 0], binning_x: 0, binning_y: 0,
    roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false } };
}

// Every message of the recording, with its log time (ns after the base) in receipt order.
export function messages() {
  const m = [];
  m.push({ topic: "/tf_static", type: "tf2_msgs/msg/TFMessage", log: 0, msg: { transforms: [
    tf(0, "world", "palm", S.worldPalm), tf(0, "camera_link", "camera_optical", S.cameraLinkOptical), tf(0, "table", "table_marker", S.tableMarker)] } });
  for (let k = 0; k < S.JOINT_MESSAGES; ++k) {
    const position = S.JOINT_NAMES.map((n) => (n.startsWith("arm") ? -1.5 : S.q(S.HAND.indexOf(n), k)));
    const effort = S.JOINT_NAMES.map((n) => (n.startsWith("arm") ? 9.0 : S.effort(S.HAND.indexOf(n), k)));
    m.push({ topic: "/joint_states", type: "sensor_msgs/msg/JointState", log: k * 5000000 + 1000000,
      msg: { header: header(S.jointStampNs(k), ""), name: S.JOINT_NAMES, position, velocity: [], effort } });
  }
  for (let i = 0; i < S.TF_SAMPLES; ++i)
    m.push({ topic: "/tf", type: "tf2_msgs/msg/TFMessage", log: S.tfStampNs(i) + 200000, msg: { transforms: [tf(S.tfStampNs(i), "world", "camera_link", S.worldCameraLink(i * 0.01))] } });
  for (let i = 0; i < S.TRUTH_SAMPLES; ++i) {
    const pose = S.worldObject((S.truthStampNs(i)) * 1e-9);
    m.push({ topic: "/mocap/object", type: "geometry_msgs/msg/PoseStamped", log: S.truthStampNs(i) + 300000,
      msg: { header: header(S.truthStampNs(i), "world"), pose: { position: { x: pose.t[0], y: pose.t[1], z: pose.t[2] }, orientation: { x: pose.q[0], y: pose.q[1], z: pose.q[2], w: pose.q[3] } } } });
  }
  // The same motion capture as TransformStamped (in the world) and as Odometry (in camera_link,
  // so that its pose goes through the dynamic TF edge), every 20 ms.
  for (let i = 0; i < S.TRUTH_SAMPLES; i += 2) {
    const ns = S.truthStampNs(i);
    const pose = S.worldObject(ns * 1e-9);
    m.push({ topic: "/mocap/object_tf", type: "geometry_msgs/msg/TransformStamped", log: ns + 300000, msg: tf(ns, "world", "object", pose) });
    const local = S.cameraLinkObject(ns * 1e-9);
    m.push({ topic: "/odom", type: "nav_msgs/msg/Odometry", log: ns + 300000, msg: { header: header(ns, "camera_link"), child_frame_id: "object",
      pose: { pose: { position: { x: local.t[0], y: local.t[1], z: local.t[2] }, orientation: { x: local.q[0], y: local.q[1], z: local.q[2], w: local.q[3] } },
        covariance: new Array(36).fill(0) },
      twist: { twist: { linear: { x: 0, y: 0, z: 0 }, angular: { x: 0, y: 0, z: 0 } }, covariance: new Array(36).fill(0) } } });
  }
  for (let f = 0; f < S.FRAMES; ++f) {
    m.push({ topic: "/camera/image_raw", type: "sensor_msgs/msg/Image", log: S.frameStampNs(f) + 4000000, msg: image(f) });
    m.push({ topic: "/camera/camera_info", type: "sensor_msgs/msg/CameraInfo", log: S.frameStampNs(f) + 4000000, msg: cameraInfo(S.frameStampNs(f), S.WIDTH, S.HEIGHT) });
  }
  // Bad-input material: a camera whose info disagrees with its images, and an unsupported encoding.
  m.push({ topic: "/camera2/image_raw", type: "sensor_msgs/msg/Image", log: S.frameStampNs(0) + 4000000, msg: image(0) });
  m.push({ topic: "/camera2/camera_info", type: "sensor_msgs/msg/CameraInfo", log: S.frameStampNs(0) + 4000000, msg: cameraInfo(S.frameStampNs(0), 640, 480, 10) });
  m.push({ topic: "/camera3/image_raw", type: "sensor_msgs/msg/Image", log: S.frameStampNs(0) + 4000000, msg: image(0, "yuv422") });
  m.push({ topic: "/camera3/camera_info", type: "sensor_msgs/msg/CameraInfo", log: S.frameStampNs(0) + 4000000, msg: cameraInfo(S.frameStampNs(0), S.WIDTH, S.HEIGHT) });
  m.sort((a, b) => a.log - b.log);
  return m.map((x) => ({ ...x, log: S.stamp(x.log).ns }));
}

if (process.argv[1] && process.argv[1].endsWith("make_fixtures.mjs")) {
  const all = messages();
  for (const [file, compression] of [["synthetic.mcap", "none"], ["synthetic_zstd.mcap", "zstd"], ["synthetic_lz4.mcap", "lz4"], ["synthetic.db3", "db3"]]) {
    const w = await Ros2Writer.create(compression);
    for (const m of all) await w.add(m.topic, m.type, m.log, m.msg);
    writeFileSync(`${out}/${file}`, await w.finish());
    console.log(`${out}/${file}`);
  }
}
