"""The Python module against the C++ command line: a Tracker fed from Python gives `inhand
replay`'s estimates, sessions read without copies, bad input raises the C++ messages.

Run by ctest (python_module) with PYTHONPATH set to the module's folder and INHAND_BINARY to the
inhand command.
"""
import csv
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
        replay = os.path.join(self.tmp.name, "replay")
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
            worst = [0.0, 0.0, 0.0]

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

            tracker = track(f, set_name, each=compare)
            with self.subTest(set=set_name):
                self.assertLess(worst[0], 1e-12, "position [m]")
                self.assertLess(worst[1], 1e-12, "rotation")
                self.assertLess(worst[2], 1e-12, "biases [rad]")
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


if __name__ == "__main__":
    unittest.main()
