"""A picture of a pyrobosim run: ``plan-bridge run WORLD --snapshot run.svg``.

The world's map (rooms, hallways - closed ones hatched, locked ones with a red
outline -, locations, object spawns and their objects), each robot's executed drives
(:attr:`~.world.RobosimWorld.trails`) and its final pose, under a title line (target,
goal, outcome, simulated time, distance). SVG is written here (plain text, no
dependency); PNG goes through matplotlib, when it is installed.

In the SVG, the map is drawn in world coordinates (metres) inside ``<g
id="map">`` (one transform flips y): every room, hallway, location and spawn is one
``<polygon>`` with a ``class`` (``room``, ``hallway`` [``closed``] [``locked``],
``location``, ``spawn``) and ``data-name``; every object a ``<circle
class="object">``; every robot's drives one ``<path class="trail" data-robot=...>``
and its final pose a ``<g class="robot">``.

The viewer shows the same drawing while a mission runs (:func:`scene_picture`, without
the title line): the runner emits it as a ``scene`` event at the mission's start, at
the end of every step and when the world's events change it (docs/introspection.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol
from xml.sax.saxutils import escape, quoteattr

__all__ = [
    "FORMATS",
    "TRAIL_CHUNK",
    "PicturedWorld",
    "picture_problem",
    "picture_title",
    "scene_of",
    "scene_picture",
    "svg_text",
    "write_picture",
]

#: The picture formats by suffix.
FORMATS = (".svg", ".png")
_SCALE = 80.0  # SVG pixels per metre
_MARGIN = 0.5  # metres around the map
_TITLE_PX = 44.0
Point = tuple[float, float]
#: Poses of a trail drawn on one line of a picture (and dropped together from a world's
#: trails: :data:`~.world.TRAIL_POINTS`).
TRAIL_CHUNK = 40


class PicturedWorld(Protocol):
    """What a picture shows of a world
    (:class:`~plan_bridge.robosim.world.RobosimWorld`)."""

    @property
    def sim(self) -> Any:
        """The pyrobosim world."""

    @property
    def trails(self) -> dict[str, list[list[list[float]]]]:
        """Each robot's executed drives, polylines of ``[x, y]`` points."""

    @property
    def distance_m(self) -> float:
        """Metres the robots drove."""

    def now(self) -> float:
        """Simulated seconds."""


@dataclass(frozen=True)
class Shape:
    """A polygon of the map: its kind (room, hallway, location, spawn) and outline."""

    kind: str
    name: str
    outline: tuple[Point, ...]
    color: str
    closed: bool = False
    locked: bool = False


@dataclass(frozen=True)
class RobotMark:
    """A robot: its drives (polylines) and its final pose."""

    name: str
    color: str
    trail: tuple[tuple[Point, ...], ...]
    pose: tuple[float, float, float]
    radius: float


@dataclass
class Scene:
    """What a picture shows, in world coordinates (metres)."""

    shapes: list[Shape] = field(default_factory=list)
    objects: list[tuple[str, Point, str]] = field(default_factory=list)
    robots: list[RobotMark] = field(default_factory=list)

    def points(self) -> Iterator[Point]:
        for shape in self.shapes:
            yield from shape.outline
        for _, xy, _ in self.objects:
            yield xy
        for robot in self.robots:
            for part in robot.trail:
                yield from part
            yield robot.pose[0], robot.pose[1]

    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) of everything drawn."""
        points = list(self.points()) or [(0.0, 0.0)]
        xs, ys = [p[0] for p in points], [p[1] for p in points]
        return min(xs), min(ys), max(xs), max(ys)


def picture_problem(path: str | Path) -> str | None:
    """Why ``path`` cannot be written (its format, or a missing package); None if it can."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        return f"--snapshot {path}: give a .svg or .png file"
    if suffix == ".png":
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            return (
                f"--snapshot {path}: a PNG needs the matplotlib package, which is not "
                f"installed (pip install matplotlib); or write an .svg"
            )
    return None


def picture_title(target: str, goal: str, outcome: str, figures: dict[str, Any]) -> str:
    """The title line: target, goal, outcome, simulated time, distance."""
    goal = " ".join(goal.split())
    if len(goal) > 90:
        goal = goal[:87] + "..."
    reached = "goal reached" if figures.get("goal_reached") else "goal not reached"
    return (
        f"{target} | {goal} | {outcome}, {reached} | "
        f"{float(figures.get('sim_time_s', 0.0)):.1f} s simulated | "
        f"{float(figures.get('distance_m', 0.0)):.1f} m driven"
    )


def _hex(color: Any, default: str = "#888888") -> str:
    try:
        r, g, b = (float(c) for c in list(color)[:3])
    except (TypeError, ValueError):
        return default
    return "#" + "".join(f"{round(max(0.0, min(1.0, c)) * 255):02x}" for c in (r, g, b))


def _outlines(geometry: Any) -> list[tuple[Point, ...]]:
    parts = getattr(geometry, "geoms", [geometry])
    return [
        tuple((float(x), float(y)) for x, y, *_ in part.exterior.coords)
        for part in parts
        if getattr(part, "exterior", None) is not None and not part.is_empty
    ]


def scene_of(world: PicturedWorld) -> Scene:
    """The scene of a world as it is now, with its robots' trails."""
    sim = world.sim
    scene = Scene()

    def add(kind: str, entity: Any, **flags: bool) -> None:
        color = _hex(getattr(entity, "viz_color", None))
        for outline in _outlines(entity.polygon):
            scene.shapes.append(Shape(kind, str(entity.name), outline, color, **flags))

    for room in sim.rooms:
        add("room", room)
    for hall in sim.hallways:
        add("hallway", hall, closed=not hall.is_open, locked=bool(hall.is_locked))
    for location in sim.locations:
        add("location", location, closed=not location.is_open, locked=bool(location.is_locked))
        for spawn in location.children:
            add("spawn", spawn)
    held = {id(r.manipulated_object) for r in sim.robots if r.manipulated_object is not None}
    for obj in sim.objects:
        if id(obj) not in held:
            scene.objects.append(
                (str(obj.name), (float(obj.pose.x), float(obj.pose.y)), _hex(obj.viz_color))
            )
    for robot in sim.robots:
        pose = robot.get_pose()
        trail = tuple(
            tuple((float(x), float(y)) for x, y in part)
            for part in world.trails.get(robot.name, [])
        )
        scene.robots.append(
            RobotMark(
                str(robot.name),
                _hex(getattr(robot, "color", None), "#cc00cc"),
                trail,
                (float(pose.x), float(pose.y), float(pose.get_yaw())),
                float(getattr(robot, "radius", 0.15) or 0.15),
            )
        )
    return scene


# -- SVG -------------------------------------------------------------------------------
_STYLE = """
text { font-family: sans-serif; fill: #222; }
polygon.room { fill-opacity: 0.18; stroke-width: 2; }
polygon.hallway { fill: #d9d9d9; stroke: #777; stroke-width: 1; }
polygon.hallway.closed { fill: url(#closed); stroke: #444; stroke-dasharray: 4 3; }
polygon.locked { stroke: #c00000 !important; stroke-width: 2.5 !important; }
polygon.location { fill-opacity: 0.55; stroke: #444; stroke-width: 1; }
polygon.location.closed { stroke-dasharray: 3 2; }
polygon.spawn { fill: none; stroke: #333; stroke-width: 0.8; stroke-dasharray: 2 2; }
circle.object { stroke: #222; stroke-width: 0.8; }
path.trail { fill: none; stroke-width: 2.5; stroke-linejoin: round; stroke-linecap: round; }
.robot circle { fill-opacity: 0.85; stroke: #000; stroke-width: 1; }
.robot line { stroke: #000; stroke-width: 2; }
.label { font-size: 11px; }
.label.room { font-size: 13px; font-weight: bold; fill-opacity: 0.8; }
.title { font-size: 14px; font-weight: bold; }
.legend { font-size: 11px; fill: #444; }
"""


def _num(value: float) -> str:
    return f"{value:.3f}".rstrip("0").rstrip(".") if value else "0"


def _trail_data(trail: Sequence[Sequence[Point]]) -> str:
    """A trail's path data, :data:`TRAIL_CHUNK` poses a line: a drive adds to the
    last line, so successive pictures differ in a few lines."""
    lines = []
    for part in trail:
        if len(part) < 2:
            continue
        coords = [f"{_num(x)} {_num(y)}" for x, y in part]
        for start in range(0, len(coords), TRAIL_CHUNK):
            head = "M " if start == 0 else "L "
            lines.append(head + " L ".join(coords[start : start + TRAIL_CHUNK]))
    return "\n".join(lines)


def _pts(points: Sequence[Point]) -> str:
    return " ".join(f"{_num(x)},{_num(y)}" for x, y in points)


def svg_text(scene: Scene, title: str, *, final: bool = True) -> str:
    """The SVG document of a scene (map in world coordinates, y up). No ``title``: no
    title line. ``final=False``: the robots' poses are not the run's last (a viewer's
    picture of a moment, :func:`scene_picture`)."""
    x0, y0, x1, y1 = scene.bounds()
    x0, y0, x1, y1 = x0 - _MARGIN, y0 - _MARGIN, x1 + _MARGIN, y1 + _MARGIN
    width = (x1 - x0) * _SCALE
    lines = _wrap(title, int(width / 9)) if title else []
    top = _TITLE_PX + 18 * (len(lines) - 1) if lines else 8.0
    height = (y1 - y0) * _SCALE + top + 22
    pose_word = "final pose" if final else "pose"

    def px(x: float, y: float) -> Point:
        return (x - x0) * _SCALE, top + (y1 - y) * _SCALE

    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height:.0f}" '
        f'viewBox="0 0 {width:.0f} {height:.0f}">',
        f"<style>{_STYLE}</style>",
        # In the map's units (metres): hatching of closed hallways.
        '<defs><pattern id="closed" width="0.12" height="0.12" patternUnits="userSpaceOnUse" '
        'patternTransform="rotate(45)"><rect width="0.12" height="0.12" fill="#eeeeee"/>'
        '<line x1="0" y1="0" x2="0" y2="0.12" stroke="#666" stroke-width="0.04"/></pattern></defs>',
        '<rect width="100%" height="100%" fill="white"/>',
        *(
            f'<text class="title" x="10" y="{20 + 18 * i}">{escape(line)}</text>'
            for i, line in enumerate(lines)
        ),
        f'<g id="map" transform="translate({_num(-x0 * _SCALE)} {_num(top + y1 * _SCALE)}) '
        f'scale({_num(_SCALE)} {_num(-_SCALE)})">',
    ]
    for shape in scene.shapes:
        classes = " ".join(
            [
                shape.kind,
                *(["closed"] if shape.closed else []),
                *(["locked"] if shape.locked else []),
            ]
        )
        paint = "" if shape.kind in ("hallway", "spawn") else f' fill="{shape.color}"'
        stroke = f' stroke="{shape.color}"' if shape.kind == "room" else ""
        state = " (closed)" if shape.closed else ""
        state += " (locked)" if shape.locked else ""
        out.append(
            f'<polygon class="{classes}" data-name={quoteattr(shape.name)}{paint}{stroke} '
            f'vector-effect="non-scaling-stroke" points="{_pts(shape.outline)}">'
            f"<title>{escape(shape.kind)} {escape(shape.name)}{state}</title></polygon>"
        )
    for name, (x, y), color in scene.objects:
        out.append(
            f'<circle class="object" data-name={quoteattr(name)} cx="{_num(x)}" cy="{_num(y)}" '
            f'r="0.07" fill="{color}" vector-effect="non-scaling-stroke"><title>{escape(name)}</title></circle>'
        )
    for robot in scene.robots:
        d = _trail_data(robot.trail)
        out.append(
            f'<path class="trail" data-robot={quoteattr(robot.name)} stroke="{robot.color}" '
            f'vector-effect="non-scaling-stroke" d="{d}"><title>{escape(robot.name)}: path driven</title></path>'
        )
    for robot in scene.robots:
        x, y, yaw = robot.pose
        hx, hy = x + robot.radius * 1.6 * math.cos(yaw), y + robot.radius * 1.6 * math.sin(yaw)
        out.append(
            f'<g class="robot" data-name={quoteattr(robot.name)}><title>{escape(robot.name)}: {pose_word} '
            f"x={x:.2f} y={y:.2f} yaw={math.degrees(yaw):.0f} deg</title>"
            f'<circle cx="{_num(x)}" cy="{_num(y)}" r="{_num(robot.radius)}" fill="{robot.color}" '
            f'vector-effect="non-scaling-stroke"/><line x1="{_num(x)}" y1="{_num(y)}" x2="{_num(hx)}" '
            f'y2="{_num(hy)}" vector-effect="non-scaling-stroke"/></g>'
        )
    out.append("</g>")
    out.append('<g id="labels">')
    for shape in scene.shapes:
        if shape.kind in ("room", "location"):
            cx, cy = _centre(shape.outline)
            lx, ly = px(cx, cy)
            out.append(
                f'<text class="label {shape.kind}" x="{lx:.1f}" y="{ly:.1f}" text-anchor="middle">'
                f"{escape(shape.name)}</text>"
            )
    for name, (x, y), _ in scene.objects:
        lx, ly = px(x, y)
        out.append(
            f'<text class="label object" x="{lx + 6:.1f}" y="{ly - 6:.1f}">{escape(name)}</text>'
        )
    for robot in scene.robots:
        lx, ly = px(robot.pose[0], robot.pose[1])
        out.append(
            f'<text class="label robot" x="{lx + 10:.1f}" y="{ly + 16:.1f}">{escape(robot.name)}</text>'
        )
    out.append("</g>")
    out.append(
        f'<text class="legend" x="10" y="{height - 8:.0f}">lines: paths driven; discs: {pose_word}s; '
        "hatched: closed hallway; red outline: locked</text>"
    )
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _wrap(title: str, width: int) -> list[str]:
    """The title in lines of about ``width`` characters, broken after its `` | ``."""
    lines: list[str] = []
    for part in title.split(" | "):
        if lines and len(lines[-1]) + 3 + len(part) <= width:
            lines[-1] += " | " + part
        else:
            lines.append(part)
    return lines


def _centre(outline: Sequence[Point]) -> Point:
    ring = outline[:-1] if len(outline) > 1 and outline[0] == outline[-1] else outline
    return sum(p[0] for p in ring) / len(ring), sum(p[1] for p in ring) / len(ring)


# -- PNG (matplotlib) ----------------------------------------------------------------------
def _png(scene: Scene, title: str, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, Polygon

    x0, y0, x1, y1 = scene.bounds()
    w, h = x1 - x0 + 2 * _MARGIN, y1 - y0 + 2 * _MARGIN
    figure = Figure(figsize=(max(6.0, w * 1.1), max(4.0, h * 1.1 + 0.6)), dpi=100)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot(1, 1, 1)
    for shape in scene.shapes:
        edge = "#c00000" if shape.locked else "#444444"
        if shape.kind == "room":
            patch = Polygon(
                shape.outline,
                closed=True,
                facecolor=shape.color,
                alpha=0.25,
                edgecolor=shape.color,
                lw=2,
            )
        elif shape.kind == "hallway":
            patch = Polygon(
                shape.outline,
                closed=True,
                facecolor="#eeeeee" if shape.closed else "#d9d9d9",
                hatch="///" if shape.closed else None,
                edgecolor=edge,
                ls="--" if shape.closed else "-",
                lw=2 if shape.locked else 1,
            )
        elif shape.kind == "location":
            patch = Polygon(
                shape.outline, closed=True, facecolor=shape.color, alpha=0.6, edgecolor=edge, lw=1
            )
        else:
            patch = Polygon(
                shape.outline, closed=True, fill=False, edgecolor="#333333", ls=":", lw=0.8
            )
        ax.add_patch(patch)
        if shape.kind in ("room", "location"):
            bold = "bold" if shape.kind == "room" else "normal"
            ax.text(
                *_centre(shape.outline),
                shape.name,
                ha="center",
                va="center",
                fontsize=8,
                fontweight=bold,
            )
    for name, (x, y), color in scene.objects:
        ax.add_patch(Circle((x, y), 0.07, facecolor=color, edgecolor="#222222", lw=0.8))
        ax.text(x + 0.1, y + 0.1, name, fontsize=7)
    for robot in scene.robots:
        for part in robot.trail:
            xs, ys = zip(*part, strict=True)
            ax.plot(xs, ys, color=robot.color, lw=2.2, solid_joinstyle="round")
        x, y, yaw = robot.pose
        ax.add_patch(
            Circle((x, y), robot.radius, facecolor=robot.color, edgecolor="black", alpha=0.85)
        )
        ax.plot(
            [x, x + 1.6 * robot.radius * math.cos(yaw)],
            [y, y + 1.6 * robot.radius * math.sin(yaw)],
            "k-",
        )
        ax.text(x + 0.15, y - 0.3, robot.name, fontsize=8)
    ax.set_xlim(x0 - _MARGIN, x1 + _MARGIN)
    ax.set_ylim(y0 - _MARGIN, y1 + _MARGIN)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9, fontweight="bold", wrap=True)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    figure.tight_layout()
    figure.savefig(path, format="png")


def scene_picture(world: PicturedWorld) -> tuple[str, str]:
    """The viewer's picture of ``world`` as it is now (the SVG of a ``scene`` event,
    :class:`~smach.introspection.events.SceneChanged`): the map, trails so far and the
    robots' current poses, without a title line; and its caption (simulated time,
    distance driven)."""
    svg = svg_text(scene_of(world), "", final=False)
    caption = f"{world.now():.1f} s simulated · {world.distance_m:.1f} m driven"
    return svg, caption


def write_picture(world: PicturedWorld, path: str | Path, title: str) -> Path:
    """Write the picture of ``world`` to ``path`` (.svg or .png); its absolute path."""
    problem = picture_problem(path)
    if problem is not None:
        raise ValueError(problem)
    target = Path(path)
    scene = scene_of(world)
    if target.suffix.lower() == ".svg":
        target.write_text(svg_text(scene, title), encoding="utf-8")
    else:
        _png(scene, title, target)
    return target.resolve()
