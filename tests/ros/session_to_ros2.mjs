// Writes an inhand session into a ROS 2 recording with the official tools (ros2_writer.mjs):
// the same topics as session_to_ros1.py, CDR-encoded; MCAP (none, zstd or lz4 chunks) or .db3.
//   node session_to_ros2.mjs SESSION OUT.mcap|OUT.db3 [none|zstd|lz4]
import { readFileSync, writeFileSync, existsSync } from "node:fs";
import { join } from "node:path";
import { Ros2Writer } from "./ros2_writer.mjs";

const [session, out, compression = "zstd"] = process.argv.slice(2);
const ns = (text) => {
  const [whole, frac = ""] = text.split(".");
  return BigInt(whole) * 1000000000n + BigInt((frac + "000000000").slice(0, 9)) * (text.startsWith("-") ? -1n : 1n);
};
const stamp = (n) => ({ sec: Number(n / 1000000000n), nanosec: Number(n % 1000000000n) });
const rows = (file) => {
  const path = join(session, file);
  if (!existsSync(path)) return [[], []];
  const lines = readFileSync(path, "utf8").trim().split("\n").map((l) => l.split(","));
  return [lines[0], lines.slice(1)];
};

const info = JSON.parse(readFileSync(join(session, "session.json"), "utf8"));
const w = await Ros2Writer.create(out.endsWith(".db3") ? "db3" : compression);
const messages = [];
const [header, samples] = rows("joints.csv");
const names = header.filter((h) => h.startsWith("q:")).map((h) => h.slice(2));
for (const row of samples) {
  const t = ns(row[0]);
  messages.push([t, "/joint_states", "sensor_msgs/msg/JointState", { header: { stamp: stamp(t), frame_id: "" }, name: names,
    position: row.slice(1, 1 + names.length).map(Number), velocity: [], effort: row.slice(1 + names.length).map(Number) }]);
}
const cam = info.camera;
for (const row of rows("camera.csv")[1]) {
  const t = ns(row[0]);
  const [x, y, z, qw, qx, qy, qz] = row.slice(2, 9).map(Number);
  messages.push([t, "/tf", "tf2_msgs/msg/TFMessage", { transforms: [{ header: { stamp: stamp(t), frame_id: "palm" }, child_frame_id: "camera",
    transform: { translation: { x, y, z }, rotation: { x: qx, y: qy, z: qz, w: qw } } }] }]);
  messages.push([t, "/camera/camera_info", "sensor_msgs/msg/CameraInfo", { header: { stamp: stamp(t), frame_id: "camera" }, height: cam.height,
    width: cam.width, distortion_model: "plumb_bob", d: cam.distortion ?? [0, 0, 0, 0, 0], k: [cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1],
    r: [1, 0, 0, 0, 1, 0, 0, 0, 1], p: [cam.fx, 0, cam.cx, 0, 0, cam.fy, cam.cy, 0, 0, 0, 1, 0], binning_x: 0, binning_y: 0,
    roi: { x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: false } }]);
  messages.push([t, "/camera/image", "sensor_msgs/msg/CompressedImage", { header: { stamp: stamp(t), frame_id: "camera" }, format: "png",
    data: new Uint8Array(readFileSync(join(session, row[1]))) }]);
}
for (const row of rows("groundtruth.csv")[1]) {
  const t = ns(row[0]);
  const [x, y, z, qw, qx, qy, qz] = row.slice(1, 8).map(Number);
  messages.push([t, "/object_pose", "geometry_msgs/msg/PoseStamped", { header: { stamp: stamp(t), frame_id: "palm" },
    pose: { position: { x, y, z }, orientation: { x: qx, y: qy, z: qz, w: qw } } }]);
}
messages.sort((a, b) => (a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : 0));
for (const [t, topic, type, msg] of messages) await w.add(topic, type, t, msg);
writeFileSync(out, await w.finish());
