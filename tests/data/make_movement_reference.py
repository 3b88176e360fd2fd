"""The stored reference of tests/test_export.py's movement check: a poses dataset made by the
movement package itself (its ``load_poses.from_numpy``), from planted tracks.

    python -m venv /tmp/mvenv && /tmp/mvenv/bin/pip install movement==0.15.0
    /tmp/mvenv/bin/python tests/data/make_movement_reference.py

(movement pins netCDF4 < 1.7.3, older than softcell's, so it is not in softcell's test
extra.) The tracks: one cell over 31 frames at 30 frames/s, the bot 3 cm behind its front
mark, frames 4 and 17 lost (NaN, confidence 0).
"""

from pathlib import Path

import numpy as np
from movement.io import load_poses

rng = np.random.default_rng(7)
frames = 31
t = np.arange(frames) / 30.0
bot = np.stack([2.0 + 1.5 * t, -1.0 + 0.5 * np.sin(3 * t)], axis=1)
heading = 0.4 + 2.0 * t
front = bot + 3.0 * np.stack([np.cos(heading), np.sin(heading)], axis=1)
cell = bot + rng.normal(scale=0.2, size=bot.shape)
position = np.stack([bot, front, cell], axis=2)[:, :, :, None]  # time, space, keypoints, 1
confidence = np.ones((frames, 3, 1))
for lost in (4, 17):
    position[lost] = np.nan
    confidence[lost] = 0.0
ds = load_poses.from_numpy(
    position, confidence, individual_names=["cell"], keypoint_names=["bot", "bot_front", "cell"],
    fps=30.0, source_software="planted",
)  # fmt: skip
out = Path(__file__).with_name("movement_poses_reference.nc")
ds.to_netcdf(out)
print(out, dict(ds.sizes), ds.attrs)
