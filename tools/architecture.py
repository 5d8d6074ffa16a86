"""Draw docs/img/architecture.png: facemech's layers and the imports between them, read from the
code itself (every ``import`` of src/facemech, at a module's top or inside a function).

The layers are docs/architecture.md's list (tests/docs/test_house.py checks the same list
against the same imports). Each box is a folder or a top-level module, with its lines of code;
an arrow is the imports from one box to another, its width growing with their number: grey
downward, blue inside a layer, red upward (none, while the house test passes).

Usage: python tools/architecture.py [-o docs/img/architecture.png]
"""

from __future__ import annotations

import argparse
import ast
import re
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "facemech"
DOC = ROOT / "docs" / "architecture.md"


def layer_list() -> list[tuple[str, list[str]]]:
    """[(layer name, [box names])], lowest first, from the doc's list."""
    block = DOC.read_text().split("<!-- layers -->")[1].split("<!-- /layers -->")[0]
    out = []
    for line in block.strip().splitlines():
        m = re.match(r"\d+\.\s+\*\*(\w+)\*\*\s+(.*?)\s+--", line)
        out.append((m.group(1), [n.rstrip("/") for n in re.findall(r"`([^`]+)`", m.group(2))]))
    return out


def box_of(module: str) -> str:
    """The box of a dotted module name: its folder, or the top-level module."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "_version"  # the root imports only _version


def arrows() -> Counter:
    """(from box, to box) -> number of imports."""
    count: Counter = Counter()
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC.parent).with_suffix("").parts
        module = ".".join(rel[:-1] if rel[-1] == "__init__" else rel)
        package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = (".".join(base + [node.module] if node.module else base)
                          if node.level else node.module)
                targets = [f"{target}.{a.name}" if node.module is None else target
                           for a in node.names]
            else:
                continue
            for target in targets:
                if target.startswith("facemech.") and box_of(target) != box_of(module):
                    count[box_of(module), box_of(target)] += 1
    return count


def lines_of(box: str) -> int:
    path = SRC / box
    files = path.rglob("*.py") if path.is_dir() else [path.with_suffix(".py")]
    return sum(len(f.read_text().splitlines()) for f in files)


def draw(output: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    layers = layer_list()
    level = {b: k for k, (_, boxes) in enumerate(layers) for b in boxes}
    width, row = 16.0, 1.25
    fig, ax = plt.subplots(figsize=(width, row * len(layers) + 0.8), dpi=110)
    ax.set_xlim(0, width)
    ax.set_ylim(-0.9, row * len(layers) + 0.2)
    ax.axis("off")
    centre = {}
    for k, (name, boxes) in enumerate(layers):
        y = k * row
        ax.add_patch(FancyBboxPatch((0.05, y - 0.42), width - 0.1, 0.84,
                                    boxstyle="round,pad=0.02", fc="#f3f4f7" if k % 2 else
                                    "#e9ebf0", ec="none", zorder=0))
        ax.text(0.2, y, f"{k + 1}. {name}", fontsize=12, fontweight="bold", va="center",
                color="#333")
        left, span = 2.6, width - 2.8
        step = span / len(boxes)
        for i, box in enumerate(boxes):
            # a layer of one box: left, middle or right in turn, so that arrows spread
            x = left + (step * (i + 0.5) if len(boxes) > 1 else span * (0.2, 0.5, 0.8)[k % 3])
            w = min(step * 0.86, 2.3)
            folder = (SRC / box).is_dir()
            ax.add_patch(FancyBboxPatch((x - w / 2, y - 0.28), w, 0.56,
                                        boxstyle="round,pad=0.02",
                                        fc="#ffffff" if folder else "#fffbe8",
                                        ec="#4a5a80", lw=1.2, zorder=3))
            ax.text(x, y + 0.08, box + ("/" if folder else ".py"), ha="center", va="center",
                    fontsize=10.5, zorder=4, fontweight="bold" if folder else "normal")
            ax.text(x, y - 0.15, f"{lines_of(box):,} lines", ha="center", va="center",
                    fontsize=8, color="#555", zorder=4)
            centre[box] = (x, y)
    for (a, b), n in sorted(arrows().items()):
        if a not in centre or b not in centre:
            continue
        (x0, y0), (x1, y1) = centre[a], centre[b]
        up, same = level[b] > level[a], level[b] == level[a]
        colour = "#d62728" if up else ("#3a6fc4" if same else "#8a8f99")
        if same:  # side to side, an arc inside the layer's band
            start, end = (x0, y0 - 0.28), (x1, y1 - 0.28)
            rad = 0.25 if x1 > x0 else -0.25
        else:
            start, end = (x0, y0 - 0.28 if y1 < y0 else y0 + 0.28), (x1, y1 + 0.28 if
                                                                     y1 < y0 else y1 - 0.28)
            rad = 0.06 * (1 if x1 > x0 else -1)
        ax.add_patch(FancyArrowPatch(start, end, connectionstyle=f"arc3,rad={rad}",
                                     arrowstyle="-|>", mutation_scale=9,
                                     lw=0.3 + 0.25 * min(n, 12) ** 0.5, color=colour,
                                     alpha=0.8 if up else 0.4, zorder=2))
    ax.text(width / 2, row * len(layers) - 0.05,
            "facemech: the layers, lowest first, and the imports between folders and modules "
            "(grey: downward, blue: within a layer, red: upward)", ha="center", fontsize=11)
    output.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(output, bbox_inches="tight")
    plt.close(fig)
    return output


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "docs" / "img" /
                        "architecture.png")
    print(draw(parser.parse_args().output))


if __name__ == "__main__":
    main()
