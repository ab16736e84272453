"""Keep the middle lane, follow the car ahead, smooth path: a Python planner in ~20 lines."""
import os, numpy as np

MAP = np.loadtxt(os.environ.get("OVERTAKE_MAP", os.path.join(os.path.dirname(__file__), "../../data/tracks/default.csv")))
LOOP = np.vstack([MAP, MAP[:1] + [0, 0, MAP[-1, 2] + np.hypot(*(MAP[0, :2] - MAP[-1, :2])), 0, 0]])
D, LIMIT, DT, v = 6.0, 21.5, 0.02, 0.0  # lane centre (m), target speed (m/s), step (s), speed now

def xy(s, d):  # Frenet to map: along the waypoints' polyline, d along their normals
    s = np.mod(s, LOOP[-1, 2])
    return [np.interp(s, LOOP[:, 2], LOOP[:, k]) + d * np.interp(s, LOOP[:, 2], LOOP[:, k + 3]) for k in (0, 1)]

def plan(t):
    global v
    px, py, n = list(t["previous_path_x"][:20]), list(t["previous_path_y"][:20]), min(len(t["previous_path_x"]), 20)
    s0 = t["s"] + n * DT * v  # about where the kept path ends
    L = LOOP[-1, 2]  # gaps to the cars in the lane when the kept path ends, across the loop's seam:
    gaps = [(c[5] + np.hypot(c[3], c[4]) * n * DT - s0 + L / 2) % L - L / 2 for c in t["sensor_fusion"] if abs(c[6] - D) < 3]
    gap = min([g for g in gaps if g > -5] + [1e9])
    v = max(v - 0.1, 0.0) if gap < 35 else min(v + 0.1, LIMIT)  # brake or speed up by 0.1 m/s
    x0, y0 = (px[-1], py[-1]) if n else (t["x"], t["y"])
    xb, yb = (px[-2], py[-2]) if n > 1 else (x0 - np.cos(np.radians(t["yaw"])), y0 - np.sin(np.radians(t["yaw"])))
    yaw = np.arctan2(y0 - yb, x0 - xb)  # the kept path's end heading (radians; telemetry yaw is degrees)
    ax, ay = xy(s0 + np.array([30.0, 60.0]), D)  # anchors ahead in the lane, to the car's frame:
    lx = np.r_[-np.hypot(x0 - xb, y0 - yb), 0, (ax - x0) * np.cos(yaw) + (ay - y0) * np.sin(yaw)]
    ly = np.r_[0, 0, -(ax - x0) * np.sin(yaw) + (ay - y0) * np.cos(yaw)]
    f = np.poly1d(np.polyfit(lx, ly, 3))  # a cubic through the 4 points
    sx = np.arange(1, 51 - n) * max(v, 0.1) * DT * 30 / np.hypot(30, f(30))  # spaced for speed v
    return px + list(x0 + sx * np.cos(yaw) - f(sx) * np.sin(yaw)), py + list(y0 + sx * np.sin(yaw) + f(sx) * np.cos(yaw))
