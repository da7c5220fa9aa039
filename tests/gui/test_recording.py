"""Recording from the window: a recorder process writes every sample of the chosen topics to MCAP
(the ROS 2 message schemas, CDR as it came) and CSV. Read back with an independent MCAP reader
(mcap_ros2 decodes each message from the schema text in the file alone), the recording holds what
the recorder says, the same numbers as the CSV, and — checked against the RT task's own cycle
counter, recorded alongside — every row the task ran between two of its statistics samples, also
when the gateway was stopped (SIGSTOP) for a few hundred rows meanwhile: it publishes every row
since its last from the bridge's row history once it runs again."""
import csv
import os
import signal
import time

from mcap.reader import make_reader
from mcap_ros2.reader import read_ros2_messages

from conftest import figure

LONG = 20_000


def test_a_recording_accounts_for_every_row_the_rt_side_sent(qtbot, deployment, shots, window):
    d, w, live = deployment, window, window.live
    qtbot.waitUntil(lambda: w.system.state_of(d.master) == "ENABLED", timeout=LONG)
    cp, stats = f"rt/{d.master}/measured_cp", f"rt/{d.master}/period_statistics"
    directory = os.path.join(shots, "recording")
    w.toggle_recording(directory, topics=[cp, stats])
    qtbot.waitUntil(lambda: live.recording()["ready"], timeout=LONG)
    qtbot.wait(1000)
    # The gateway late by 300 rows (its process stopped; fewer than the bridge's history of
    # 1024, and within the RT side's 500 ms client timeout and DDS's 1 s lease).
    gateway_pid = live.gateways()[live.components()[d.master]["gateway"]]["pid"]
    os.kill(gateway_pid, signal.SIGSTOP)
    try:
        time.sleep(0.3)
    finally:
        os.kill(gateway_pid, signal.SIGCONT)
    qtbot.wait(2000)  # three seconds of a 1 kHz arm in all
    summary = w.toggle_recording()
    assert "recorded" in w.statusBar().currentMessage()
    path = os.path.join(directory, "recording.mcap")
    assert path in summary["files"]

    with open(path, "rb") as f:
        reader = make_reader(f)
        header, info = reader.get_header(), reader.get_summary()
    assert header.profile == "ros2"
    schemas = {c.topic: info.schemas[c.schema_id].name for c in info.channels.values()}
    assert schemas == {f"/{d.master}/measured_cp": "geometry_msgs/msg/PoseStamped",
                       f"/{d.master}/period_statistics": "saw_msgs/msg/TaskStatistics"}, schemas
    assert {c.message_encoding for c in info.channels.values()} == {"cdr"}

    poses, cycles = [], []
    for m in read_ros2_messages(path):
        if m.channel.topic.endswith("measured_cp"):
            poses.append((m.publish_time_ns, m.ros_msg.pose.position.x, m.ros_msg.pose.position.z))
        else:
            cycles.append((m.publish_time_ns, m.ros_msg.cycles))
    assert len(poses) == summary["topics"][cp]["samples"] > 1000, (len(poses), summary)
    assert len(cycles) == summary["topics"][stats]["samples"] > 100
    with open(summary["topics"][cp]["csv"]) as f:
        rows = list(csv.reader(f))[1:]
    assert len(rows) == len(poses)
    assert all(abs(float(r[1]) - x) < 1e-12 and abs(float(r[3]) - z) < 1e-12 for r, (_, x, z) in zip(rows, poses))

    # Against the RT side: the task ran (last cycles - first cycles) cycles between its first and
    # last statistics sample, each a row with a pose: the recording holds every one, the stalled
    # gateway's rows included; DDS lost none on loopback. (Were any missing, the recorder would
    # say how many, and the status bar MISSED.)
    (ta, ca), (tb, cb) = cycles[0], cycles[-1]
    between = sum(1 for t, _, _ in poses if ta < t <= tb)
    said = summary["topics"][cp]
    assert said["lost"] == 0 and said["rejected"] == 0, said
    assert said["rt_rows"] == cb - ca
    assert between == cb - ca and said["upstream_missed"] == 0, (between, said, cb - ca)
    assert said["missed"] == 0, said
    assert "MISSED" not in w.statusBar().currentMessage()
    figure(f"recorded {len(poses)} poses; between two statistics samples the RT task ran {cb - ca} cycles, "
           f"the recording holds {between} of their rows ({said['upstream_missed']} never published by "
           f"the gateway, said by the recorder; the gateway stopped for 300 ms meanwhile); DDS lost {said['lost']}")
