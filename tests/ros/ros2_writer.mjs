// Writes ROS 2 recordings with the official tools: MCAP through @mcap/core (schemas encoded as
// "ros2msg", messages as "cdr" by @foxglove/rosmsg2-serialization), or rosbag2's sqlite3 .db3
// (its `topics` and `messages` tables, through sql.js).
import { createRequire } from "node:module";

const require = createRequire(import.meta.url);
const { McapWriter, TempBuffer } = require("./node/node_modules/@mcap/core");
const { MessageWriter } = require("./node/node_modules/@foxglove/rosmsg2-serialization");
const { parse } = require("./node/node_modules/@foxglove/rosmsg");
const zstd = require("./node/node_modules/@foxglove/wasm-zstd");
const lz4js = require("./node/node_modules/lz4js");

const SEP = "\n================================================================================\n";
const TIME = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
const HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id";
const VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z";
const POINT = "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z";
const QUATERNION = "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
const POSE = "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation";
const TRANSFORM = "MSG: geometry_msgs/Transform\nVector3 translation\nQuaternion rotation";
const TRANSFORM_STAMPED = "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\nTransform transform";
const ROI = "MSG: sensor_msgs/RegionOfInterest\nuint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify";

export const DEFINITIONS = {
  "sensor_msgs/msg/JointState": ["std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort", HEADER, TIME],
  "sensor_msgs/msg/Image": ["std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data", HEADER, TIME],
  "sensor_msgs/msg/CompressedImage": ["std_msgs/Header header\nstring format\nuint8[] data", HEADER, TIME],
  "sensor_msgs/msg/CameraInfo": ["std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\nfloat64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\nuint32 binning_y\nRegionOfInterest roi", HEADER, TIME, ROI],
  "tf2_msgs/msg/TFMessage": ["geometry_msgs/TransformStamped[] transforms", TRANSFORM_STAMPED, HEADER, TIME, TRANSFORM, VECTOR3, QUATERNION],
  "geometry_msgs/msg/PoseStamped": ["std_msgs/Header header\nPose pose", HEADER, TIME, POSE, POINT, QUATERNION],
  "geometry_msgs/msg/TransformStamped": ["std_msgs/Header header\nstring child_frame_id\nTransform transform", HEADER, TIME, TRANSFORM, VECTOR3, QUATERNION],
  "nav_msgs/msg/Odometry": ["std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist",
    HEADER, TIME, "MSG: geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance", POSE, POINT, QUATERNION,
    "MSG: geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance", "MSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular", VECTOR3],
};

export class Ros2Writer {
  static async create(compression) {
    const w = new Ros2Writer();
    w.compression = compression;
    w.writers = new Map();
    w.channels = new Map();
    if (compression === "db3") {
      const initSqlJs = require("./node/node_modules/sql.js");
      const SQL = await initSqlJs();
      w.db = new SQL.Database();
      // rosbag2's sqlite3 storage schema (rosbag2_storage_default_plugins, Humble).
      w.db.run("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);");
      w.db.run("INSERT INTO schema VALUES (3, 'humble');");
      w.db.run("CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);");
      w.db.run("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);");
      w.db.run("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);");
      w.db.run("CREATE INDEX timestamp_idx ON messages (timestamp ASC);");
      return w;
    }
    await zstd.isLoaded;
    w.buffer = new TempBuffer();
    const options = { writable: w.buffer, useChunks: compression !== "none", chunkSize: 32 * 1024 };
    if (compression === "zstd") options.compressChunk = (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) });
    if (compression === "lz4") options.compressChunk = (data) => ({ compression: "lz4", compressedData: lz4js.compress(data) });
    w.mcap = new McapWriter(options);
    await w.mcap.start({ profile: "ros2", library: "inhand tests (@mcap/core)" });
    return w;
  }

  writerFor(type) {
    if (!this.writers.has(type)) {
      const text = DEFINITIONS[type].join(SEP);
      this.writers.set(type, { text, writer: new MessageWriter(parse(text, { ros2: true })) });
    }
    return this.writers.get(type);
  }

  async add(topic, type, logNs, msg) {
    const { text, writer } = this.writerFor(type);
    const data = writer.writeMessage(msg);
    if (this.db) {
      if (!this.channels.has(topic)) {
        const id = this.channels.size + 1;
        this.db.run("INSERT INTO topics VALUES (?, ?, ?, 'cdr', '')", [id, topic, type]);
        this.channels.set(topic, id);
      }
      this.db.run("INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", [this.channels.get(topic), Number(logNs), data]);
      return;
    }
    if (!this.channels.has(topic)) {
      const schemaId = await this.mcap.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode(text) });
      this.channels.set(topic, await this.mcap.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() }));
    }
    this.sequence = (this.sequence ?? 0) + 1;
    await this.mcap.addMessage({ channelId: this.channels.get(topic), sequence: this.sequence, logTime: BigInt(logNs), publishTime: BigInt(logNs), data });
  }

  async finish() {
    if (this.db) return Buffer.from(this.db.export());
    await this.mcap.end();
    return Buffer.from(this.buffer.get());
  }
}
