#!/usr/bin/python3
"""Writes the synthetic recording (synthetic.mjs holds the formulas) as a ROS 1 bag with
Debian's own rosbag writer (python3-rosbag). Run with Debian's python:
    /usr/bin/python3 tests/ros/make_ros1_fixture.py tests/ros/fixtures/synthetic.bag
"""
import math
import sys

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, JointState
from tf2_msgs.msg import TFMessage

HAND = ["index_abduction", "index_flex1", "index_flex2", "index_flex3", "middle_abduction", "middle_flex1",
        "middle_flex2", "middle_flex3", "ring_abduction", "ring_flex1", "ring_flex2", "ring_flex3", "thumb_abduction",
        "thumb_flex1", "thumb_flex2", "thumb_flex3"]
BASE_NS = 1700000000 * 1000000000 + 250000000
JOINT_NAMES = ["arm_joint_1", "arm_joint_2"] + HAND[::-1]
WIDTH, HEIGHT = 64, 48
K = [60, 0, 31.5, 0, 60, 23.5, 0, 0, 1]
D = [0.01, -0.002, 0.0005, 0.0003, 0]


def q(j, k):
    return 0.1 + 0.02 * j + 0.001 * k


def effort(j, k):
    return 0.01 * j - 0.0005 * k


def joint_stamp_ns(k):
    kk = {100: 101, 101: 100, 51: 50}.get(k, k)
    return kk * 5000000


def frame_stamp_ns(f):
    return f * 50000000 + 2500000


def about_z(a):
    return [0, 0, math.sin(a / 2), math.cos(a / 2)]


def about_x(a):
    return [math.sin(a / 2), 0, 0, math.cos(a / 2)]


def stamp(ns):
    return rospy.Time(nsecs=BASE_NS + ns)


def transform(ns, parent, child, t, r):
    m = TransformStamped()
    m.header.stamp = stamp(ns)
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = t
    m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = r
    return m


def image(f, encoding="rgb8"):
    m = Image()
    m.header.stamp = stamp(frame_stamp_ns(f))
    m.header.frame_id = "camera_optical"
    m.height, m.width, m.encoding, m.is_bigendian, m.step = HEIGHT, WIDTH, encoding, 0, WIDTH * 3
    data = bytearray(WIDTH * HEIGHT * 3)
    for y in range(HEIGHT):
        for x in range(WIDTH):
            i = (y * WIDTH + x) * 3
            data[i:i + 3] = bytes([(x * 4 + f * 7) & 255, (y * 5 + f) & 255, ((x ^ y) * 3) & 255])
    m.data = bytes(data)
    return m


def camera_info(ns, width, height):
    m = CameraInfo()
    m.header.stamp = stamp(ns)
    m.header.frame_id = "camera_optical"
    m.height, m.width, m.distortion_model = height, width, "plumb_bob"
    m.D, m.K = D, K
    m.R = [1, 0, 0, 0, 1, 0, 0, 0, 1]
    m.P = [60, 0, 31.5, 0, 0, 60, 23.5, 0, 0, 0, 1, 0]
    return m


def messages():
    out = []
    out.append(("/tf_static", 0, TFMessage(transforms=[
        transform(0, "world", "palm", [0.1, 0.2, 0.3], about_z(math.pi / 6)),
        transform(0, "camera_link", "camera_optical", [0, 0, 0], [-0.5, 0.5, -0.5, 0.5]),
        transform(0, "table", "table_marker", [1, 0, 0], [0, 0, 0, 1])])))
    for k in range(200):
        m = JointState()
        m.header.stamp = stamp(joint_stamp_ns(k))
        m.name = JOINT_NAMES
        m.position = [-1.5 if n.startswith("arm") else q(HAND.index(n), k) for n in JOINT_NAMES]
        m.effort = [9.0 if n.startswith("arm") else effort(HAND.index(n), k) for n in JOINT_NAMES]
        out.append(("/joint_states", k * 5000000 + 1000000, m))
    for i in range(101):
        s = i * 0.01
        out.append(("/tf", i * 10000000 + 200000, TFMessage(transforms=[
            transform(i * 10000000, "world", "camera_link", [0.5 + 0.1 * s, -0.2, 0.4], about_z(0.2 * s))])))
    for i in range(100):
        ns = i * 10000000 + 1000000
        s = ns * 1e-9
        m = PoseStamped()
        m.header.stamp = stamp(ns)
        m.header.frame_id = "world"
        m.pose.position.x, m.pose.position.y, m.pose.position.z = 0.15, 0.2 + 0.05 * s, 0.35
        r = about_x(0.1 * s)
        m.pose.orientation.x, m.pose.orientation.y, m.pose.orientation.z, m.pose.orientation.w = r
        out.append(("/mocap/object", ns + 300000, m))
    # The same motion capture as TransformStamped (world) and Odometry (camera_link), every 20 ms.
    for i in range(0, 100, 2):
        ns = i * 10000000 + 1000000
        s = ns * 1e-9
        out.append(("/mocap/object_tf", ns + 300000, transform(ns, "world", "object", [0.15, 0.2 + 0.05 * s, 0.35], about_x(0.1 * s))))
        m = Odometry()
        m.header.stamp = stamp(ns)
        m.header.frame_id = "camera_link"
        m.child_frame_id = "object"
        m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = 0.05, 0.1 + 0.02 * s, -0.03
        r = about_x(0.3 * s)
        m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z, m.pose.pose.orientation.w = r
        out.append(("/odom", ns + 300000, m))
    for f in range(10):
        out.append(("/camera/image_raw", frame_stamp_ns(f) + 4000000, image(f)))
        out.append(("/camera/camera_info", frame_stamp_ns(f) + 4000000, camera_info(frame_stamp_ns(f), WIDTH, HEIGHT)))
    out.append(("/camera2/image_raw", frame_stamp_ns(0) + 4000000, image(0)))
    out.append(("/camera2/camera_info", frame_stamp_ns(0) + 4000000, camera_info(frame_stamp_ns(0), 640, 480)))
    out.append(("/camera3/image_raw", frame_stamp_ns(0) + 4000000, image(0, "yuv422")))
    out.append(("/camera3/camera_info", frame_stamp_ns(0) + 4000000, camera_info(frame_stamp_ns(0), WIDTH, HEIGHT)))
    out.sort(key=lambda m: m[1])
    return out


if __name__ == "__main__":
    with rosbag.Bag(sys.argv[1], "w") as bag:
        for topic, log_ns, msg in messages():
            bag.write(topic, msg, stamp(log_ns))
    print(sys.argv[1])
