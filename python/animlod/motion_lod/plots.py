"""Charts of a motion LoD chain: joint importance, key posture, error against joint count."""

from __future__ import annotations

import os

import numpy as np

from .chain import MotionLodChain


def plot_chain(path: str | os.PathLike, chain: MotionLodChain, names: list[str]) -> None:
    """Write a PNG with three panels: importance per joint (Eq. 3) as bars, the key posture
    (Section 4.2) as a stick figure seen from the front, and each level's mean and max joint
    position error against its joint count."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io.atomic import atomic_write

    analysis = chain.analysis
    level0 = chain.levels[0].frozen
    skeleton = level0.skeleton
    joints = np.flatnonzero(~skeleton.end_sites)
    figure, (bars, stick, errors) = plt.subplots(1, 3, figsize=(18, 6), gridspec_kw={"width_ratios": [2, 1, 1]})

    order = joints[np.argsort(-analysis.importance[joints], kind="stable")]
    bars.bar(range(order.size), analysis.importance[order], color="tab:blue")
    bars.set_xticks(range(order.size), [names[j] for j in order], rotation=90, fontsize=7)
    bars.set_ylabel("importance eps_j (Eq. 3)")
    bars.set_title("joint importance (eliminated from the right)")

    key = level0.key_positions
    for joint in range(1, skeleton.joint_count):
        parent = skeleton.parents[joint]
        stick.plot(key[[parent, joint], 0], key[[parent, joint], 1], color="0.3", linewidth=2)
    # Colours span the joints that can be frozen: the root's importance would flatten them.
    top = max(float(analysis.importance[analysis.priority].max()) if analysis.priority else 0.0, 1e-12)
    stick.scatter(
        key[joints, 0], key[joints, 1], c=analysis.importance[joints], cmap="viridis", vmin=0, vmax=top, zorder=3
    )
    stick.set_aspect("equal")
    stick.set_title("key posture (front, coloured by importance)")

    counts = [level.report.joint_count for level in chain.levels]
    errors.plot(counts, [level.report.mean_error for level in chain.levels], "o-", label="mean")
    errors.plot(counts, [level.report.max_error for level in chain.levels], "s--", label="max")
    errors.set_xlabel("joints")
    errors.set_ylabel("joint position error (asset units)")
    errors.invert_xaxis()
    errors.legend()
    errors.set_title("error against joint count")
    figure.tight_layout()
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format="png", dpi=110)
    plt.close(figure)
