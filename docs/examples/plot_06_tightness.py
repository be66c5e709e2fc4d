"""
How tight is a set? The exact reference
=======================================

The information set's interval of the forecast miss against the exact one (linear
programs over every state consistent with the measurements so far) at three times of
the Fig. 3 engagement: the ratio of the widths is 1 for an exact set.
"""

import json
import tempfile
from pathlib import Path

import matplotlib.image as mpimg
import matplotlib.pyplot as plt
from kalman_vs_infoset.experiments.cli import main

# the command writes a report and a figure: into a temporary folder, read back here
with tempfile.TemporaryDirectory() as tmp:
    out = Path(tmp)
    main(["tightness", "kp_fig3", "--times", "10,60,90", "--out", str(out)])
    (report,) = out.glob("*.json")
    rows = json.loads(report.read_text())
    (png,) = out.glob("*.png")
    image = mpimg.imread(png)
print(json.dumps(rows, indent=1)[:600])

# %%
# The figure the command drew:
fig, ax = plt.subplots(figsize=(8, 5))
ax.imshow(image)
ax.set_axis_off()
