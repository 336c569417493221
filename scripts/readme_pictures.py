"""Make the README's pictures (docs/img/) from a tour folder.

    clsamp tour --out tour && python scripts/readme_pictures.py tour docs/img

Downsizes the radial-mean and convergence figures and sets the AO renders of section 3
side by side with their MSE against the reference.
"""

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

RENDERS = ("reference", "random", "jittered", "poisson_disk", "ccvt", "sobol_owen")


def main(tour, out):
    tour, out = Path(tour), Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for name, width in (("radial_means", 7.0), ("convergence", 11.0)):
        image = mpimg.imread(tour / "img" / f"{name}.png")
        h, w = image.shape[:2]
        fig = plt.figure(figsize=(width, width * h / w))
        ax = fig.add_axes([0, 0, 1, 1])
        ax.imshow(image)
        ax.axis("off")
        fig.savefig(out / f"{name}.png", dpi=80)
        plt.close(fig)
    data = json.loads((tour / "tour.json").read_text())["sections"]["render"]["data"]
    fig, axes = plt.subplots(1, len(RENDERS), figsize=(2.0 * len(RENDERS), 2.6))
    for ax, name in zip(axes, RENDERS, strict=True):
        ax.imshow(mpimg.imread(tour / "img" / f"render_{name}.png"), cmap="gray", vmin=0, vmax=1)
        key = name.replace("sobol_owen", "sobol:owen")
        ax.set_title("reference" if name == "reference" else f"{key}\nMSE {data[key]['mse']:.2e}",
                     fontsize=8)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(out / "renders.png", dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    main(*sys.argv[1:3])
