#!/usr/bin/python3
"""A video from Python: a mission decided by the built-in igbnet policy, one
frame per decision step from Mission.render, encoded by ffmpeg (H.264).

    PYTHONPATH=build/python examples/python/video.py renders/python.mp4 [SCENARIO]

(`aia render` films the physics between steps too; this shows the state
after each step.)
"""
import subprocess
import sys

import aia

out = sys.argv[1] if len(sys.argv) > 1 else "renders/python.mp4"
scenario = sys.argv[2] if len(sys.argv) > 2 else "scenarios/default.yaml"
width, height, fps = 640, 480, 4
m = aia.Mission(scenario, seed=1)
policy = aia.builtin_policy("igbnet")
ffmpeg = subprocess.Popen(
    ["ffmpeg", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt",
     "rgb24", "-s", f"{width}x{height}", "-r", str(fps), "-i", "-",
     "-c:v", "libx264", "-pix_fmt", "yuv420p", out], stdin=subprocess.PIPE)
frames = 0
while True:
    ffmpeg.stdin.write(m.render(width, height).tobytes())
    frames += 1
    if m.done:
        break
    m.step(policy.decide(m))
ffmpeg.stdin.close()
if ffmpeg.wait() != 0:
    sys.exit("ffmpeg failed")
print(f"wrote {out}: {frames} frames, success {m.success} in {m.steps} steps")
