"""msdeform's Python example (README, section Python): bend the right end of the built-in bumpy plane
up by 45 degrees with ARAP and save the result as bent.off in the current folder.

    /usr/bin/python3 python/example.py          (PYTHONPATH=build/python before installing)
"""
import msdeform

V, F, _, _ = msdeform.scene("lift", 10000)  # the bumpy plane: unit square, bumps of height 0.05
labels = msdeform.region(V, fixed=lambda V: V[:, 0] < 0.2, handles=[lambda V: V[:, 0] > 0.8])
arap = msdeform.Deformer("arap")
arap.prepare(V, F, labels)
T = msdeform.rotation("y", -45, about=(0.8, 0.5, 0))  # one 4x4 per handle
bent = arap.deform([T])
msdeform.write_mesh("bent.off", bent, F)

print(f"wrote bent.off: {len(V)} vertices, {arap.frame_report.iterations} ARAP iterations, "
      f"handle error {msdeform.handle_error(V, bent, labels, [T]):.1e}")
