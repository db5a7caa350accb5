#!/usr/bin/python3
"""The live ROS 1 node against `inhand replay`, over real ROS: a rosmaster of its own on
127.0.0.1, the node as its own process, and a player (rospy) that publishes a simulated session
as a robot would (/joint_states with the torques as effort, /tf palm -> camera, CameraInfo and
the PNG frames as CompressedImage, in time order at the session's rate) and records what the
node publishes.

Run 1, --deterministic: every set's pose after every joint state equals replay's estimate
(positions within 1e-6 m) wherever the messages arrived in time order (at least 95 % of them, and
the last); the health topic and the TF frames are there. Run 2, threaded as on a robot: the
latency from a JointState's publication to its pose's arrival (two ROS hops) and the node's own
from arrival to publication, p50 and p99, printed; the node keeps up (every state gets a pose).

    node_test.py INHAND INHAND_ROS_NODE WORKDIR
"""
import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from decimal import Decimal


def ns(text):
    return int(Decimal(text) * 1000000000)


def rows(path):
    with open(path) as f:
        r = list(csv.reader(f))
    return r[0], r[1:]


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(predicate, seconds, what):
    end = time.time() + seconds
    while time.time() < end:
        if predicate():
            return
        time.sleep(0.05)
    raise SystemExit("FAIL: timed out waiting for " + what)


def percentile(values, f):
    v = sorted(values)
    return v[min(len(v) - 1, int(f * len(v)))] if v else float("nan")


def main(inhand, node_bin, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    session, replay = os.path.join(work, "session"), os.path.join(work, "replay")
    sets = ["jt", "jta"]
    subprocess.run([inhand, "simulate", "ketchup-power-grasp", "--seed", "1", "--out", session],
                   check=True, stdout=subprocess.DEVNULL)
    # Stamps are whole nanoseconds; the simulator's times are not (1.1260000000000001 s): the
    # replay reads a copy of the session with its times as the node sees them.
    for name in ("joints.csv", "camera.csv", "groundtruth.csv"):
        path = os.path.join(session, name)
        if os.path.exists(path):
            header, body = rows(path)
            with open(path, "w", newline="") as f:
                w = csv.writer(f, lineterminator="\n")
                w.writerow(header)
                w.writerows([repr(ns(r[0]) / 1e9)] + r[1:] for r in body)
    subprocess.run([inhand, "replay", session, "--modalities", ",".join(sets), "--no-video",
                    "--no-timeline", "--out", replay], check=True, stdout=subprocess.DEVNULL)

    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port, ROS_HOSTNAME="127.0.0.1",
               ROS_HOME=os.path.join(work, "ros"))
    os.environ.update(env)
    master = subprocess.Popen(["rosmaster", "--core", "-p", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        import rosgraph
        wait_for(lambda: rosgraph.Master("/probe").is_online(), 30, "rosmaster")
        import rospy
        from geometry_msgs.msg import PoseWithCovarianceStamped, TransformStamped
        from sensor_msgs.msg import CameraInfo, CompressedImage, Image, JointState
        from std_msgs.msg import String
        from tf2_msgs.msg import TFMessage
        rospy.init_node("player", anonymous=True, disable_signals=True)
        failures = []

        info = json.load(open(os.path.join(session, "session.json")))
        start = info["initial_estimate"]
        T = start["T_PO"]
        start_arg = " ".join(repr(v) for v in T["xyz"] + T["quat_wxyz"])
        sigma_arg = " ".join(repr(start[k]) for k in
                             ("sigma_position", "sigma_orientation", "sigma_joint_bias"))
        jheader, joints = rows(os.path.join(session, "joints.csv"))
        names = [h[2:] for h in jheader if h.startswith("q:")]
        _, frames = rows(os.path.join(session, "camera.csv"))
        cam = info["camera"]
        images = {row[0]: open(os.path.join(session, row[1]), "rb").read() for row in frames}

        # Every message of the session in time order; an image after the joint states up to
        # its capture time, as the replay fuses it.
        timeline = [(ns(r[0]), 0, r) for r in joints] + [(ns(r[0]), 1, r) for r in frames]
        timeline.sort(key=lambda e: (e[0], e[1]))

        # Run 2's camera at 30 Hz: each instant shows the session's newest frame (its image, its
        # camera pose) with the instant's stamp.
        camera_30hz, f = [], 0
        for k in range(int((ns(joints[-1][0]) - ns(joints[0][0])) * 30 // 1000000000) + 1):
            stamp = ns(joints[0][0]) + k * 1000000000 // 30
            while f + 1 < len(frames) and ns(frames[f + 1][0]) <= stamp:
                f += 1
            camera_30hz.append((stamp, 1, frames[f]))
        timeline_30hz = sorted([(ns(r[0]), 0, r) for r in joints] + camera_30hz,
                               key=lambda e: (e[0], e[1]))

        def run(deterministic, timeline):
            tag = "deterministic" if deterministic else "threaded"
            stats_path = os.path.join(work, "stats_%s.json" % tag)
            args = [node_bin, "--hand", os.path.join(session, info["hand"]["urdf"]),
                    "--object", os.path.join(session, info["object"]["model"]),
                    "--sets", ",".join(sets), "--effort-is", "external",
                    "--compressed-image", "/camera/image/compressed",
                    "--palm-frame", "palm", "--start-sigma", sigma_arg,
                    "--time-origin", "0", "--stats-out", stats_path,
                    "__name:=inhand_" + tag]
            # Run 1 gives the start as numbers, run 2 as a TF frame (static, published first).
            args += ["--deterministic", "--start", start_arg] if deterministic else \
                ["--start-frame", "object_guess", "--annotated-rate", "2"]
            log = open(os.path.join(work, "node_%s.log" % tag), "w")
            node = subprocess.Popen(args, env=env, stdout=log, stderr=subprocess.STDOUT)
            received = {s: {} for s in sets}
            health, tf_children, annotated = [], set(), []
            lock = threading.Lock()

            def on_pose(set_name):
                def cb(m):
                    with lock:
                        p = m.pose.pose.position
                        received[set_name][m.header.stamp.to_nsec()] = (
                            (p.x, p.y, p.z), time.monotonic())
                return cb

            def on_tf(m):
                with lock:
                    tf_children.update(t.child_frame_id for t in m.transforms)

            base = "/inhand_" + tag
            subs = [rospy.Subscriber(base + "/%s/pose" % s, PoseWithCovarianceStamped,
                                     on_pose(s), tcp_nodelay=True, queue_size=10000)
                    for s in sets]
            subs += [rospy.Subscriber(base + "/%s/health" % s, String,
                                      lambda m: health.append(json.loads(m.data)))
                     for s in sets]
            subs.append(rospy.Subscriber("/tf", TFMessage, on_tf, queue_size=10000))
            if not deterministic:
                subs.append(rospy.Subscriber(base + "/annotated", Image,
                                             lambda m: annotated.append(m), queue_size=100))
            pub_js = rospy.Publisher("/joint_states", JointState, queue_size=10000,
                                     tcp_nodelay=True)
            pub_tf = rospy.Publisher("/tf", TFMessage, queue_size=1000)
            pub_ci = rospy.Publisher("/camera/camera_info", CameraInfo, queue_size=100)
            pub_im = rospy.Publisher("/camera/image/compressed", CompressedImage, queue_size=100)
            pub_static = rospy.Publisher("/tf_static", TFMessage, queue_size=10, latch=True)
            guess = TransformStamped()
            guess.header.frame_id, guess.child_frame_id = "palm", "object_guess"
            guess.transform.translation.x, guess.transform.translation.y, \
                guess.transform.translation.z = T["xyz"]
            g = guess.transform.rotation
            g.w, g.x, g.y, g.z = T["quat_wxyz"]
            pub_static.publish(TFMessage(transforms=[guess]))
            try:
                wait_for(lambda: all(p.get_num_connections() > 0
                                     for p in (pub_js, pub_tf, pub_ci, pub_im)) and
                         all(s.get_num_connections() > 0 for s in subs[:len(sets)]) or
                         node.poll() is not None, 120, "the node's subscriptions")
                if node.poll() is not None:
                    raise SystemExit("FAIL: the node exited: " +
                                     open(os.path.join(work, "node_%s.log" % tag)).read())
                time.sleep(0.5)
                sent = {}
                t0_wall, t0 = time.monotonic(), timeline[0][0]
                for stamp, kind, r in timeline:
                    # The session's own pace: joint states at their rate.
                    delay = (stamp - t0) * 1e-9 - (time.monotonic() - t0_wall)
                    if delay > 0:
                        time.sleep(delay)
                    st = rospy.Time(nsecs=stamp)
                    if kind == 0:
                        m = JointState()
                        m.header.stamp = st
                        m.name = names
                        m.position = [float(v) for v in r[1:1 + len(names)]]
                        m.effort = [float(v) for v in r[1 + len(names):]]
                        sent[stamp] = time.monotonic()
                        pub_js.publish(m)
                    else:
                        tf = TransformStamped()
                        tf.header.stamp, tf.header.frame_id, tf.child_frame_id = st, "palm", "camera"
                        tr = tf.transform.translation
                        tr.x, tr.y, tr.z = [float(v) for v in r[2:5]]
                        q = tf.transform.rotation
                        q.w, q.x, q.y, q.z = [float(v) for v in r[5:9]]
                        if not deterministic:
                            pub_tf.publish(TFMessage(transforms=[tf]))
                        ci = CameraInfo()
                        ci.header.stamp, ci.header.frame_id = st, "camera"
                        ci.width, ci.height, ci.distortion_model = cam["width"], cam["height"], "plumb_bob"
                        ci.D = cam.get("distortion", [0, 0, 0, 0, 0])
                        ci.K = [cam["fx"], 0, cam["cx"], 0, cam["fy"], cam["cy"], 0, 0, 1]
                        pub_ci.publish(ci)
                        time.sleep(0.002)  # intrinsics (and TF) before the image
                        im = CompressedImage()
                        im.header.stamp, im.header.frame_id, im.format = st, "camera", "png"
                        im.data = images[r[0]]
                        pub_im.publish(im)
                        if deterministic:
                            # The camera's TF 10 ms after its image, as a lagging TF comes: the
                            # node must wait for it rather than hold the previous frame's (the
                            # palm has moved since; jta ended 0.2-1 mm off replay when it held).
                            time.sleep(0.01)
                            pub_tf.publish(TFMessage(transforms=[tf]))
                            time.sleep(0.03)  # the image reaches the node before the next state
                wait_for(lambda: all(len(received[s]) >= len(joints) for s in sets) or
                         node.poll() is not None, 60, "a pose for every joint state")
            finally:
                node.send_signal(signal.SIGINT)
                node.wait(30)
                log.close()
                for x in subs + [pub_js, pub_tf, pub_ci, pub_im, pub_static]:
                    x.unregister()
            for s in sets:  # kept for a look when the comparison fails
                with open(os.path.join(work, "poses_%s_%s.csv" % (tag, s)), "w") as f:
                    for k in sorted(received[s]):
                        f.write("%d,%r,%r,%r\n" % ((k,) + received[s][k][0]))
            if node.returncode != 0:
                raise SystemExit("FAIL: node exit %d: %s" % (node.returncode, open(
                    os.path.join(work, "node_%s.log" % tag)).read()[-3000:]))
            return received, sent, health, tf_children, annotated, json.load(open(stats_path))

        # Bad input: one line naming what is missing or wrong, exit 2, nothing published.
        for extra, expected in (([], "--start"), (["--start", "0 0 0 1 0 0 0", "--sets", "jx"],
                                                  "'jx'")):
            r = subprocess.run([node_bin, "--hand", os.path.join(session, info["hand"]["urdf"]),
                                "--object", os.path.join(session, info["object"]["model"]),
                                "__name:=inhand_bad"] + extra, env=env, capture_output=True,
                               text=True, timeout=120)
            if r.returncode != 2 or expected not in r.stderr:
                failures.append("bad input %s: exit %d, %r" % (extra, r.returncode, r.stderr))
            else:
                print("bad input %s: %s" % (extra, r.stderr.strip()))

        # Run 1: against the replay.
        received, _, health, tf_children, _, stats = run(True, timeline)
        _, est = rows(os.path.join(replay, "estimates.csv"))
        # A pose is published when its joint state arrives; an image captured at that same stamp
        # comes after it and counts from the next joint state on, whereas replay's row at that
        # stamp has it fused: those samples are not compared.
        frame_stamps = {ns(r[0]) for r in frames}
        for s in sets:
            expected = {ns(r[0]): tuple(float(v) for v in r[2:5]) for r in est
                        if r[1] == s and ns(r[0]) not in frame_stamps}
            got = received[s]
            diffs = [max(abs(a - b) for a, b in zip(got[k][0], expected[k]))
                     for k in expected if k in got]
            close = sum(d <= 1e-6 for d in diffs)
            last = max(expected)
            last_diff = max(abs(a - b) for a, b in zip(got[last][0], expected[last])) \
                if last in got else float("inf")
            print("%s: %d of the %d poses not at a frame's stamp within 1e-6 m of replay; "
                  "largest difference %.3g m; the last %.3g m; images fused %d of %d" %
                  (s, close, len(expected), max(diffs), last_diff,
                   stats["sets"][s]["images_fused"], len(frames)))
            if len(got) != len(joints):
                failures.append("%s: %d poses for %d joint states" % (s, len(got), len(joints)))
            if close < 0.95 * len(expected):
                failures.append("%s: only %d of %d poses within 1e-6 m" % (s, close, len(expected)))
            if not last_diff <= 1e-6:
                failures.append("%s: the last pose is %.3g m from replay's" % (s, last_diff))
            if stats["sets"][s]["images_fused"] < len(frames) - 1:
                failures.append("%s: %d of %d images fused" %
                                (s, stats["sets"][s]["images_fused"], len(frames)))
            if not any(h["set"] == s and h["state"] in ("ok", "uncertain", "inconsistent", "lost")
                       for h in health):
                failures.append("%s: no health message" % s)
            if "object_" + s not in tf_children:
                failures.append("%s: no TF frame object_%s" % (s, s))

        # Run 2: threaded, the latency; started from a TF frame at the same pose, its first pose
        # is run 1's.
        first_stamp = ns(joints[0][0])
        first_1 = {s: received[s][first_stamp][0] for s in sets}
        received, sent, _, _, annotated, stats = run(False, timeline_30hz)
        # The annotated image: ~2 Hz over the session, at a camera image's stamp, the size of the
        # camera, both sets' outlines in their colours (jt blue, jta orange).
        duration = (ns(joints[-1][0]) - ns(joints[0][0])) * 1e-9
        camera_stamps = {stamp for stamp, _, _ in camera_30hz}
        print("annotated images: %d received, %d published over %.1f s" %
              (len(annotated), stats.get("annotated_images", -1), duration))
        if not 2 * duration - 3 <= len(annotated) <= 2 * duration + 1:
            failures.append("%d annotated images in %.1f s at 2 Hz" % (len(annotated), duration))
        for m in annotated:
            if (m.encoding, m.width, m.height, m.step) != ("rgb8", cam["width"], cam["height"],
                                                           3 * cam["width"]) or \
                    m.header.stamp.to_nsec() not in camera_stamps or \
                    len(m.data) != 3 * cam["width"] * cam["height"]:
                failures.append("annotated image %s %dx%d at %d" % (
                    m.encoding, m.width, m.height, m.header.stamp.to_nsec()))
                break
        if annotated:
            last = annotated[-1]
            with open(os.path.join(work, "annotated.ppm"), "wb") as f:
                f.write(b"P6 %d %d 255\n" % (last.width, last.height) + bytes(last.data))
            pixels = bytes(last.data)
            counts = {name: sum(1 for i in range(0, len(pixels), 3)
                                if pixels[i:i + 3] == bytes(rgb))
                      for name, rgb in (("jt", (31, 119, 220)), ("jta", (255, 140, 0)))}
            print("last annotated image: pixels in jt's colour %d, in jta's %d" %
                  (counts["jt"], counts["jta"]))
            for name, n in counts.items():
                if n < 100:
                    failures.append("the annotated image has %d pixels of %s's outline" % (n, name))
        for s in sets:
            d = max(abs(a - b) for a, b in zip(received[s][first_stamp][0], first_1[s]))
            print("%s: the first pose started from the TF frame is %.3g m from run 1's" % (s, d))
            if not d <= 1e-9:
                failures.append("%s: started from the TF frame %.3g m from --start" % (s, d))
        lat = [(received["jt"][k][1] - sent[k]) * 1e6 for k in sent if k in received["jt"]]
        print("threaded: %d joint states; publication -> pose received p50 %.0f us, p99 %.0f us "
              "(two ROS hops through rospy); the node from arrival to publication p50 %.0f us, "
              "p99 %.0f us, max %.0f us; images fused jt %d, jta %d of %d" %
              (len(lat), percentile(lat, 0.5), percentile(lat, 0.99),
               stats["latency_us"]["p50"], stats["latency_us"]["p99"], stats["latency_us"]["max"],
               stats["sets"]["jt"]["images_fused"], stats["sets"]["jta"]["images_fused"],
               len(camera_30hz)))
        for s in sets:
            if len(received[s]) != len(joints):
                failures.append("threaded %s: %d poses for %d joint states" %
                                (s, len(received[s]), len(joints)))
        if stats["sets"]["jta"]["images_fused"] < len(frames):
            failures.append("threaded jta: %d of %d images fused" %
                            (stats["sets"]["jta"]["images_fused"], len(camera_30hz)))
        rospy.signal_shutdown("done")
        if failures:
            raise SystemExit("FAIL: " + "; ".join(failures))
        print("ok")
    finally:
        master.terminate()
        master.wait(10)


if __name__ == "__main__":
    main(*sys.argv[1:4])
