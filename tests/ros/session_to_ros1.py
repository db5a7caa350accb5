#!/usr/bin/python3
"""Writes an inhand session into a ROS 1 bag with Debian's rosbag writer (python3-rosbag), as a
robot would have recorded it: /joint_states (JointState, effort = the session's torques),
/camera/image (CompressedImage: the session's PNG files as they are), /camera/camera_info,
/tf (palm -> camera at each frame's stamp), /object_pose (PoseStamped in the palm frame).
Stamps are the session's t (nanoseconds, exactly from the decimal text).
    /usr/bin/python3 session_to_ros1.py SESSION OUT.bag
"""
import csv
import json
import os
import sys
from decimal import Decimal

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from sensor_msgs.msg import CameraInfo, CompressedImage, JointState
from tf2_msgs.msg import TFMessage


def ns(text):
    return int(Decimal(text) * 1000000000)


def rows(path):
    if not os.path.exists(path):
        return [], []
    with open(path) as f:
        r = list(csv.reader(f))
    return r[0], r[1:]


def main(session, out):
    info = json.load(open(os.path.join(session, "session.json")))
    palm = "palm"
    with rosbag.Bag(out, "w") as bag:
        header, samples = rows(os.path.join(session, "joints.csv"))
        names = [h[2:] for h in header if h.startswith("q:")]
        for row in samples:
            m = JointState()
            t = rospy.Time(nsecs=ns(row[0]))
            m.header.stamp = t
            m.name = names
            m.position = [float(v) for v in row[1:1 + len(names)]]
            m.effort = [float(v) for v in row[1 + len(names):]]
            bag.write("/joint_states", m, t)
        cam = info.get("camera")
        _, frames = rows(os.path.join(session, "camera.csv"))
        for row in frames:
            t = rospy.Time(nsecs=ns(row[0]))
            tf = TransformStamped()
            tf.header.stamp, tf.header.frame_id, tf.child_frame_id = t, palm, "camera"
            tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z = [float(v) for v in row[2:5]]
            r = tf.transform.rotation
            r.w, r.x, r.y, r.z = [float(v) for v in row[5:9]]
            bag.write("/tf", TFMessage(transforms=[tf]), t)
            ci = CameraInfo()
            ci.header.stamp, ci.header.frame_id = t, "camera"
            ci.width, ci.height, ci.distortion_model = cam["width"], cam["height"], "plumb_bob"
            ci.D = cam.get("distortion", [0, 0, 0, 0, 0])
            ci.K = [cam["fx"], 0, cam["cx"], 0, cam["fy"], cam["cy"], 0, 0, 1]
            bag.write("/camera/camera_info", ci, t)
            img = CompressedImage()
            img.header.stamp, img.header.frame_id, img.format = t, "camera", "png"
            img.data = open(os.path.join(session, row[1]), "rb").read()
            bag.write("/camera/image", img, t)
        _, truth = rows(os.path.join(session, "groundtruth.csv"))
        for row in truth:
            t = rospy.Time(nsecs=ns(row[0]))
            m = PoseStamped()
            m.header.stamp, m.header.frame_id = t, palm
            m.pose.position.x, m.pose.position.y, m.pose.position.z = [float(v) for v in row[1:4]]
            o = m.pose.orientation
            o.w, o.x, o.y, o.z = [float(v) for v in row[4:8]]
            bag.write("/object_pose", m, t)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
