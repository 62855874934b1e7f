"""`trol ros2`'s timing from a ROS 2 peer's side (Cyclone DDS on loopback), for docs/ros2.md:
the joint_states rate a subscriber receives, and the latency from sending a
FollowJointTrajectory goal to the arm's first motion seen in joint_states (and to the
send_goal reply). Run as a script, not by pytest:

    TROL_ROS2_BIN=target/release/trol-ros2 target/py/bin/python tests/ros2/bench_ros2.py [--goals N]

It starts its own node on the embedded simulator at real time, on a random domain.
"""

import argparse
import os
import platform
import random
import statistics
import time

import test_ros2 as t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--goals", type=int, default=10, help="trajectory goals to time (default 10)")
    ap.add_argument("--rate", type=float, default=50.0, help="the node's joint_states rate, Hz")
    args = ap.parse_args()
    # Look every millisecond: the figures are the node's, not this script's pauses.
    t.POLL = 0.001
    domain = random.randint(1, 200)
    node = t.Node(domain, "bench", time_scale=1)
    try:
        assert "/bench/trol_a465" in node.first, node.first
        dp = t.DomainParticipant(domain)
        states = t.states_reader(dp, "bench")
        t.wait_for("joint states", lambda: True if states.take(N=10) else None)
        # The rate a subscriber receives, over 5 s.
        start = time.monotonic()
        got = 0
        while time.monotonic() - start < 5.0:
            got += sum(1 for s in states.take(N=100) if isinstance(s, t.JointState))
            time.sleep(0.05)
        rate = got / (time.monotonic() - start)
        assert t.call_trigger(dp, "bench", "home", 1).success
        action = t.Action(dp, "bench")
        to_reply, to_motion = [], []
        q = 0.0
        for k in range(args.goals):
            q = 0.3 if q == 0.0 else 0.0
            states.take(N=1000)
            goal = t.trajectory_goal(t.JOINTS, [(0.5, [q, 0, 0, 0, 0, 0])])
            gid = t.UUID(uuid=list(random.randbytes(16)))
            sent = time.monotonic()
            action.send.call(lambda g, s: t.SendGoalRequest(client_guid=g, sequence_number=s, goal_id=gid, goal=goal))
            to_reply.append(time.monotonic() - sent)
            start_q = 0.3 - q

            def moved() -> bool | None:
                for s in states.take(N=100):
                    if isinstance(s, t.JointState) and abs(s.position[0] - start_q) > 1e-3:
                        return True
                return None

            t.wait_for("the arm's motion", moved, 30)
            to_motion.append(time.monotonic() - sent)
            r = action.outcome(gid)
            assert r.status == t.SUCCEEDED, r.result.error_string
        load = os.getloadavg()
        print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
        print(f"joint_states asked at {args.rate:g} Hz, received at {rate:.1f} Hz")
        print(f"goal -> send_goal reply: median {statistics.median(to_reply) * 1e3:.1f} ms, "
              f"max {max(to_reply) * 1e3:.1f} ms ({args.goals} goals)")
        print(f"goal -> first motion in joint_states: median {statistics.median(to_motion) * 1e3:.1f} ms, "
              f"max {max(to_motion) * 1e3:.1f} ms")
    finally:
        node.stop()


if __name__ == "__main__":
    main()
