"""The Python module against the C++ command line: a Tracker fed from Python gives `inhand
replay`'s estimates, sessions read without copies, bad input raises the C++ messages.

Run by ctest (python_module) with PYTHONPATH set to the module's folder and INHAND_BINARY to the
inhand command.
"""
import csv
import json
import os
import subprocess
import tempfile
import threading
import unittest

import numpy as np

import inhand

BINARY = os.environ["INHAND_BINARY"]


def run(*args):
    result = subprocess.run([BINARY, *args], capture_output=True, text=True)
    if result.returncode != 0:
        raise AssertionError(f"inhand {' '.join(args)} exited {result.returncode}:\n"
                             f"{result.stdout}{result.stderr}")


def rotation(qw, qx, qy, qz):
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ])


class Fixture:
    """One simulated session (ketchup power grasp, tags on the bottle) and its replay."""
    _instance = None

    @classmethod
    def get(cls):
        if cls._instance is None:
            cls._instance = cls()
        return cls._instance

    def __init__(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="inhand-python-")
        self.session_dir = os.path.join(self.tmp.name, "session")
        run("simulate", "ketchup-power-grasp", "--seed", "3", "--noise", "paper", "--out",
            self.session_dir)
        self.replay_dir = replay = os.path.join(self.tmp.name, "replay")
        run("replay", self.session_dir, "--modalities", "j,jt,jta,jtf", "--no-video", "--out", replay)
        self.rows = {}
        with open(os.path.join(replay, "estimates.csv"), newline="") as f:
            for row in csv.DictReader(f):
                self.rows.setdefault(row["set"], []).append(row)
        self.session = inhand.Session(self.session_dir)
        self.hand, self.object, self.columns = self.session.models()


def track(fixture, set_name, threaded=False, each=None):
    """The robot's loop over the session, as the README shows it."""
    s = fixture.session
    tracker = inhand.Tracker(fixture.hand, fixture.object, set_name, threaded=threaded,
                             horizon=100.0 if threaded else 0.5,
                             history_samples=len(s.t) + 1 if threaded else 2048,
                             max_queued_images=1000 if threaded else 2)
    tracker.start(s.t[0], s.initial_pose, s.sigma_position, s.sigma_orientation,
                  s.sigma_joint_bias)
    q, tau = s.q[:, fixture.columns], s.tau[:, fixture.columns]
    frames, next_frame = s.frame_times, 0
    vision = "a" in set_name or "f" in set_name
    for k, t in enumerate(s.t):
        tracker.add_joint_sample(t, q[k], tau[k])
        while next_frame < len(frames) and frames[next_frame] <= t + 1e-9:
            if vision:
                tracker.add_image(frames[next_frame], s.image(next_frame),
                                  s.camera_pose(next_frame), s.K, s.distortion)
            next_frame += 1
        if each:
            each(k, tracker)
    tracker.wait_for_images()
    return tracker


class TrackerFromPython(unittest.TestCase):
    def test_every_set_gives_replays_estimates(self):
        f = Fixture.get()
        for set_name in ("j", "jt", "jta", "jtf"):
            rows = f.rows[set_name]
            bias_columns = [c for c in rows[0] if c.startswith("bias:")]
            self.assertEqual(len(rows), len(f.session.t))
            worst = [0.0, 0.0, 0.0, 0.0]

            def compare(k, tracker):
                row = rows[k]
                self.assertEqual(float(row["t"]), f.session.t[k])
                T = tracker.pose()
                p = np.array([float(row[c]) for c in ("px", "py", "pz")])
                R = rotation(*(float(row[c]) for c in ("qw", "qx", "qy", "qz")))
                b = np.array([float(row[c]) for c in bias_columns])
                worst[0] = max(worst[0], np.abs(T[:3, 3] - p).max())
                worst[1] = max(worst[1], np.abs(T[:3, :3] - R).max())
                worst[2] = max(worst[2], np.abs(tracker.biases() - b).max())
                # replay's sigma is the claimed covariance's (relative: the CSV's printed digits)
                C = tracker.claimed_pose_covariance()
                sigma = np.array([float(row[c]) for c in ("sigma_px", "sigma_py", "sigma_pz")])
                worst[3] = max(worst[3], np.abs(np.sqrt(np.diag(C)[:3]) / sigma - 1).max())

            tracker = track(f, set_name, each=compare)
            with self.subTest(set=set_name):
                self.assertLess(worst[0], 1e-12, "position [m]")
                self.assertLess(worst[1], 1e-12, "rotation")
                self.assertLess(worst[2], 1e-12, "biases [rad]")
                self.assertLess(worst[3], 1e-6, "claimed sigma")
                stats = tracker.stats()
                self.assertEqual(stats["samples"], len(f.session.t))
                if set_name in ("jta", "jtf"):
                    self.assertGreater(stats["images_fused"], 40)
                health = tracker.health()
                self.assertIn(health["state"], ("ok", "uncertain", "inconsistent", "lost"))
                P = tracker.covariance()
                self.assertEqual(P.shape, (6 + f.hand.num_joints,) * 2)
                self.assertTrue(np.allclose(P, P.T))

    def test_threaded_feeding_from_two_python_threads_equals_inline(self):
        f = Fixture.get()
        inline = track(f, "jta")
        results = {}

        def worker(name):
            tracker = track(f, "jta", threaded=True)
            results[name] = tracker.pose(), tracker.stats()

        threads = [threading.Thread(target=worker, args=(n,)) for n in ("a", "b")]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        for name in ("a", "b"):
            pose, stats = results[name]
            self.assertEqual(stats["images_fused"], inline.stats()["images_fused"])
            self.assertEqual(stats["images_dropped_busy"], 0)
            np.testing.assert_array_equal(pose, inline.pose())


class SessionArrays(unittest.TestCase):
    def test_joint_arrays_are_views_into_the_session(self):
        s = Fixture.get().session
        q1, q2 = s.q, s.q
        self.assertTrue(np.shares_memory(q1, q2), "q is a view, not a copy per access")
        self.assertTrue(np.shares_memory(s.t, s.t))
        self.assertFalse(q1.flags.writeable)
        self.assertEqual(q1.shape, (len(s.t), len(s.joint_names)))
        # The first sample against joints.csv as written.
        with open(os.path.join(s.dir, "joints.csv"), newline="") as fh:
            first = next(csv.DictReader(fh))
        for j, name in enumerate(s.joint_names):
            self.assertEqual(q1[0, j], float(first["q:" + name]))
            self.assertEqual(s.tau[0, j], float(first["tau:" + name]))

    def test_images_camera_and_truth(self):
        s = Fixture.get().session
        image = s.image(0)
        self.assertEqual(image.dtype, np.uint8)
        self.assertEqual(image.shape[2], 3)
        K = s.K
        self.assertEqual(K[2, 2], 1.0)
        T = s.camera_pose(0)
        self.assertTrue(np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3)))
        self.assertIsNotNone(s.truth(s.t[0]))


class BadInput(unittest.TestCase):
    def test_errors_carry_the_cpp_messages(self):
        f = Fixture.get()
        with self.assertRaisesRegex(inhand.InputError, "no-such-session: session directory not found"):
            inhand.Session(os.path.join(f.tmp.name, "no-such-session"))
        with self.assertRaisesRegex(ValueError, "set: 'jx': unknown letter 'x'"):
            inhand.Tracker(f.hand, f.object, "jx")
        with self.assertRaisesRegex(ValueError, "tracker parameters.*unknown parameter 'no_such_parameter'"):
            inhand.Tracker(f.hand, f.object, "jt", params={"no_such_parameter": 1})
        tracker = inhand.Tracker(f.hand, f.object, "jt")
        with self.assertRaisesRegex(ValueError, "add_joint_sample before start"):
            tracker.add_joint_sample(0.0, np.zeros(f.hand.num_joints))
        with self.assertRaisesRegex(ValueError, "T_PO: the top-left 3x3 block is not a rotation"):
            scaled = np.eye(4)
            scaled[:3, :3] *= 2
            tracker.start(0.0, scaled)
        with self.assertRaisesRegex(ValueError, r"T_PO: last row is not \(0 0 0 1\)"):
            tracker.start(0.0, 2 * np.eye(4))
        tracker.start(0.0, f.session.initial_pose)
        with self.assertRaisesRegex(ValueError, r"q: 3 values, the hand has \d+ joints"):
            tracker.add_joint_sample(0.01, np.zeros(3))
        with self.assertRaisesRegex(ValueError, "image: expected"):
            tracker.add_image(0.01, np.zeros((4, 4, 5), np.uint8), np.eye(4), f.session.K)


def svg_axes(path):
    """Each axes group of a matplotlib SVG: its tick labels and every text in it."""
    import xml.etree.ElementTree as ET
    g = "{http://www.w3.org/2000/svg}g"
    text = "{http://www.w3.org/2000/svg}text"

    def labels(node, prefix):
        return ["".join(t.itertext()) for e in node.iter(g) if e.get("id", "").startswith(prefix)
                for t in e.iter(text)]

    return [{"xticks": labels(a, "xtick_"), "yticks": labels(a, "ytick_"),
             "texts": ["".join(t.itertext()) for t in a.iter(text)]}
            for a in ET.parse(path).getroot().iter(g) if a.get("id", "").startswith("axes_")]


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class Commands(unittest.TestCase):
    """simulate, replay and evaluate as functions, against the command line's own runs."""

    def test_simulate_writes_the_commands_session(self):
        f = Fixture.get()
        out = os.path.join(f.tmp.name, "simulated-from-python")
        summary = inhand.simulate("ketchup-power-grasp", out, seed=3, noise="paper", images=False)
        self.assertEqual(summary["joint_samples"], len(f.session.t))
        self.assertEqual(summary["camera_frames"], 0, "images=False")
        self.assertGreater(summary["held_fraction"], 0.9)
        # The same seed and noise: the command's joints and truth, byte for byte (images do not
        # draw from the physics' random numbers).
        for name in ("joints.csv", "groundtruth.csv"):
            with open(os.path.join(out, name)) as a, open(os.path.join(f.session_dir, name)) as b:
                self.assertEqual(a.read(), b.read(), name)
        self.assertEqual(inhand.Session(out).provenance["seed"], 3)
        with self.assertRaisesRegex(ValueError, "already exists"):
            inhand.simulate("ketchup-power-grasp", out, images=False)
        with self.assertRaisesRegex(ValueError, "no-such-scenario"):
            inhand.simulate("no-such-scenario", os.path.join(f.tmp.name, "x"))
        self.assertIn("pen-fingertip", [s["name"] for s in inhand.scenarios()])

    def test_replay_returns_the_summary_it_writes(self):
        f = Fixture.get()
        out = os.path.join(f.tmp.name, "replayed-from-python")
        # Parameters as a dict: the defaults but a wider contact σ, which must change jt.
        summary = inhand.replay(f.session_dir, out, sets="jt", video=False,
                                params={"contact_sigma": 0.03})
        with open(os.path.join(out, "summary.json")) as fh:
            self.assertEqual(summary, json.load(fh))
        with open(os.path.join(out, "params.json")) as fh:
            self.assertEqual(json.load(fh)["contact_sigma"], 0.03)
        with open(os.path.join(f.replay_dir, "summary.json")) as fh:
            command = json.load(fh)["modalities"]["jt"]
        self.assertNotEqual(summary["modalities"]["jt"]["terminal_position_error_mm"],
                            command["terminal_position_error_mm"])
        # The default parameters: the command's estimates exactly.
        out = os.path.join(f.tmp.name, "replayed-defaults")
        summary = inhand.replay(f.session_dir, out, sets="jt", video=False)
        self.assertEqual(summary["modalities"]["jt"]["terminal_position_error_mm"],
                         command["terminal_position_error_mm"])
        mine = [r for r in read_rows(os.path.join(out, "estimates.csv"))]
        self.assertEqual([r["px"] for r in mine], [r["px"] for r in f.rows["jt"]])
        with self.assertRaisesRegex(ValueError, "unknown parameter 'contact_sigmaa'"):
            inhand.replay(f.session_dir, os.path.join(f.tmp.name, "y"), video=False,
                          params='{"contact_sigmaa": 1}')
        with self.assertRaisesRegex(ValueError, "--picture-memory: expected MiB"):
            inhand.replay(f.session_dir, os.path.join(f.tmp.name, "y"), video=False,
                          picture_memory=-1)

    def test_evaluate_returns_table1(self):
        f = Fixture.get()
        out = os.path.join(f.tmp.name, "evaluated-from-python")
        table = inhand.evaluate(out, scenarios="ketchup-power-grasp", seeds=1, first_seed=3,
                                sets="j,jt", jobs=1)
        with open(os.path.join(f.replay_dir, "summary.json")) as fh:
            command = json.load(fh)["modalities"]
        for set_name in ("j", "jt"):
            row = table["ketchup-power-grasp"][set_name]
            self.assertEqual(row["runs"], 1)
            self.assertAlmostEqual(row["position_mm_mean"],
                                   command[set_name]["terminal_position_error_mm"], places=9)
        # The plots, drawn by matplotlib: PNG, PDF and SVG with its text kept as text.
        for name in ("fig7_ketchup-power-grasp", "terminal_errors"):
            with open(os.path.join(out, name + ".png"), "rb") as fh:
                self.assertEqual(fh.read(8), b"\x89PNG\r\n\x1a\n")
            with open(os.path.join(out, name + ".pdf"), "rb") as fh:
                self.assertEqual(fh.read(5), b"%PDF-")
        axes = svg_axes(os.path.join(out, "fig7_ketchup-power-grasp.svg"))
        legend = [a for a in axes if not a["xticks"]]
        plots = [a for a in axes if a["xticks"]]
        self.assertEqual(len(legend), 1, "one legend row")
        self.assertEqual(legend[0]["texts"], ["j", "jt", "truth"])
        self.assertEqual(len(plots), 8, "six axes of the pose over time, two of terminal errors")
        for a in plots:
            self.assertGreaterEqual(len(a["yticks"]), 3)
            values = [float(t.replace("\u2212", "-")) for t in a["yticks"]]
            self.assertEqual(values, sorted(values), "one value axis, increasing")
        units = [t for a in plots for t in a["texts"] if t.endswith(("[mm]", "[deg]"))]
        self.assertEqual(len(units), 8, units)
        self.assertEqual(sum("t [s]" in a["texts"] for a in plots), 6)
        # The bars' value axis reaches the largest mean it shows.
        bars = [a for a in plots if "terminal position error, 1 run [mm]" in a["texts"]][0]
        self.assertEqual(bars["xticks"], ["j", "jt"])
        top = max(float(t) for t in bars["yticks"])
        self.assertGreaterEqual(top, max(table["ketchup-power-grasp"][s]["position_mm_mean"]
                                         for s in ("j", "jt")))


class WriterFromPython(unittest.TestCase):
    def test_a_session_copied_through_python_replays_the_same(self):
        f = Fixture.get()
        s = f.session
        out = os.path.join(f.tmp.name, "copied")
        with inhand.SessionWriter(out, s.hand_urdf, s.object_file, s.joint_names, K=s.K,
                                  image_size=s.image_size, distortion=s.distortion,
                                  initial_pose=s.initial_pose, sigma_position=s.sigma_position,
                                  sigma_orientation=s.sigma_orientation,
                                  sigma_joint_bias=s.sigma_joint_bias, packages=s.packages,
                                  joint_stiffness=s.joint_stiffness, name=s.name,
                                  provenance=s.provenance) as w:
            for k in range(len(s.t)):
                w.add_joint_sample(s.t[k], s.q[k], s.tau[k])
            for i, t in enumerate(s.frame_times):
                w.add_camera_frame(t, s.image(i), s.camera_pose(i))
            for t, T in s.truth_samples:
                w.add_ground_truth(t, T)
            self.assertFalse(os.path.exists(out), "nothing appears before the commit")
        with open(os.path.join(out, "joints.csv")) as a, open(os.path.join(s.dir, "joints.csv")) as b:
            self.assertEqual(a.read(), b.read())
        copy = inhand.Session(out)
        self.assertEqual(copy.name, s.name)
        np.testing.assert_array_equal(copy.image(7), s.image(7))
        for i in range(len(s.frame_times)):
            np.testing.assert_allclose(copy.camera_pose(i), s.camera_pose(i), rtol=0, atol=1e-15)
        replay = os.path.join(f.tmp.name, "copied-replay")
        inhand.replay(out, replay, sets="j,jt,jta,jtf", video=False)
        rows = read_rows(os.path.join(replay, "estimates.csv"))
        original = [r for set_name in ("j", "jt", "jta", "jtf") for r in f.rows[set_name]]
        rows.sort(key=lambda r: ("j", "jt", "jta", "jtf").index(r["set"]))
        self.assertEqual(len(rows), len(original))
        # Joints and torques are byte-identical: j and jt estimate the same poses. The camera
        # poses pass a 4x4 matrix, so their quaternions may move in the last digit, and a last
        # digit can tip one of the matching's discrete choices (a corner kept, an inlier): the
        # vision sets agree within 1e-4 (m, and in each quaternion component; measured: 1e-6
        # before features were matched only around the object, 1.1e-5 since).
        for a, b in zip(rows, original):
            bound = 0.0 if a["set"] in ("j", "jt") else 1e-4
            for c in ("px", "py", "pz", "qw", "qx", "qy", "qz"):
                self.assertLessEqual(abs(float(a[c]) - float(b[c])), bound, (a["set"], a["t"], c))

    def test_bad_input_and_an_exception_leave_nothing(self):
        f = Fixture.get()
        s = f.session
        out = os.path.join(f.tmp.name, "never-written")
        names = s.joint_names
        with self.assertRaisesRegex(RuntimeError, "boom"):
            with inhand.SessionWriter(out, s.hand_urdf, s.object_file, names) as w:
                w.add_joint_sample(0.0, np.zeros(len(names)), np.zeros(len(names)))
                w.add_joint_sample(0.1, np.zeros(len(names)), np.zeros(len(names)))
                raise RuntimeError("boom")
        self.assertFalse(os.path.exists(out))
        self.assertEqual([p for p in os.listdir(f.tmp.name) if "never-written" in p], [])
        w = inhand.SessionWriter(out, s.hand_urdf, s.object_file, names, torques=False)
        w.add_joint_sample(0.0, np.zeros(len(names)))
        with self.assertRaisesRegex(ValueError, "after the previous sample"):
            w.add_joint_sample(0.0, np.zeros(len(names)))
        with self.assertRaisesRegex(ValueError, rf"q: expected {len(names)} finite values, got 2"):
            w.add_joint_sample(0.1, np.zeros(2))
        with self.assertRaisesRegex(ValueError, "tau: the writer was made with torques=False"):
            w.add_joint_sample(0.1, np.zeros(len(names)), np.zeros(len(names)))
        with self.assertRaisesRegex(ValueError, "the writer was made without K"):
            w.add_camera_frame(0.1, np.zeros((480, 640, 3), np.uint8), np.eye(4))
        with self.assertRaisesRegex(ValueError, "expected a path inside the session"):
            w.add_file("../outside.txt", "x")
        with self.assertRaisesRegex(ValueError, "at least two joint samples"):
            w.commit()
        with self.assertRaisesRegex(ValueError, "give K and image_size"):
            inhand.SessionWriter(out, s.hand_urdf, s.object_file, names, K=s.K)
        with self.assertRaisesRegex(ValueError, "already exists"):
            inhand.SessionWriter(s.dir, s.hand_urdf, s.object_file, names)


if __name__ == "__main__":
    unittest.main()
