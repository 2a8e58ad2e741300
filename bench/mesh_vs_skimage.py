"""`kardia mesh` against scikit-image's marching_cubes (Lewiner) at the same distance from
the exact surface (run by bench/mesh-vs-skimage.sh, which makes the virtual environment).

For each surface and tolerance (SCALES: shares of kardia's default, 1% of the clip radius):
`kardia mesh` (the release binary) is timed as a whole
run, with its peak memory, and its meshing time (extraction and coarsening, as its summary
prints them: without its own accuracy measurement, check and file) is read from its summary; then scikit-image meshes the same solid (the surface's f ≤ 0
inside the clip ball: the sampled field is max(f, x² + y² + z² − R²)) on an n³ grid of
samples, n growing by 1.25× until its mesh is as close to the exact surface as kardia's.
Both meshes are measured the same way, by `kardia mesh --measure` (the root finder's
two-sided Hausdorff estimate at the grid step of the tolerance compared; for a surface the
clip sphere cuts, its surface→mesh part: see `by_s2m` below). The times compared are
medians of REPEAT (3) interleaved runs of each. The time of
scikit-image is sampling plus marching (not the interpreter's start or the file written);
peak memory is each process's maximum resident size (for scikit-image the whole Python
process, numpy and scikit-image included).
"""

import json
import os
import re
import statistics
import subprocess
import sys
import time

# name, kardia's preset arguments, f(x, y, z) in numpy, clip radius (as the preset's), and
# whether the clip sphere cuts the surface (the solid then has a cap).
PHI = (1 + 5**0.5) / 2
SURFACES = [
    ("torus", ["torus", "1", "0.35"], "(x*x + y*y + z*z + 1 - 0.35**2)**2 - 4*(x*x + y*y)", 1.05 * 1.35, False),
    ("heart", ["heart"], "(2*x*x + y*y + z*z - 1)**3 - (0.1*x*x + y*y)*z**3", 2.0, False),
    (
        "kummer",
        ["kummer", "1.3"],
        "(x*x + y*y + z*z - 1.69)**2 - (3*1.69 - 1)/(3 - 1.69)*((1 - z)**2 - 2*x*x)*((1 + z)**2 - 2*y*y)",
        2.6,
        True,
    ),
    (
        "barth_sextic",
        ["barth_sextic"],
        f"4*({PHI**2}*x*x - y*y)*({PHI**2}*y*y - z*z)*({PHI**2}*z*z - x*x)"
        f" - {1 + 2 * PHI}*(x*x + y*y + z*z - 1)**2",
        2.0,
        True,
    ),
]


def skimage_mesh(name, n, out):
    """Samples the solid's field on an n³ grid, marches it, writes a binary STL; prints JSON."""
    import numpy as np
    from skimage.measure import marching_cubes

    _, _, expr, radius, _ = next(s for s in SURFACES if s[0] == name)
    half = radius * 1.02
    started = time.perf_counter()
    pts = np.linspace(-half, half, n)
    step = pts[1] - pts[0]
    field = np.empty((n, n, n))
    y = pts[None, :, None]
    z = pts[None, None, :]
    for i in range(0, n, 8):  # slabs of x, to keep the temporaries small
        x = pts[i : i + 8, None, None]
        f = eval(expr, {"x": x, "y": y, "z": z})
        field[i : i + 8] = np.maximum(f, x * x + y * y + z * z - radius * radius)
    verts, faces, _, _ = marching_cubes(field, 0.0, spacing=(step, step, step), method="lewiner")
    elapsed = time.perf_counter() - started
    verts = verts - half
    tri = np.zeros(len(faces), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    tri["v"] = verts[faces]
    with open(out, "wb") as fh:
        fh.write(b"\0" * 80 + np.uint32(len(faces)).tobytes())
        fh.write(tri.tobytes())
    print(json.dumps({"time": elapsed, "triangles": int(len(faces))}))


def timed(cmd):
    """Runs cmd under /usr/bin/time; returns (stdout, seconds, peak resident MB)."""
    r = subprocess.run(["/usr/bin/time", "-f", "TIME %e %M"] + cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{r.stdout}{r.stderr}")
    t = re.findall(r"TIME ([\d.]+) (\d+)", r.stderr)[-1]
    return r.stdout, float(t[0]), int(t[1]) / 1024


def measure(kardia, preset, tolerance, path):
    """(Hausdorff estimate, surface→mesh distance, samples beyond the search reach), measured
    at the grid step of `tolerance`."""
    out = subprocess.run(
        [kardia, "mesh", "--preset", *preset, "--tolerance", repr(tolerance), "--measure", path],
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise SystemExit(out.stdout + out.stderr)
    number = lambda pattern: float(re.search(pattern + r" ([\d.e+-]+)", out.stdout).group(1))
    beyond = int(re.search(r"(\d+) samples beyond", out.stdout).group(1))
    return number("Hausdorff estimate"), number("surface→mesh"), beyond


def watertight(path):
    import trimesh

    return "yes" if trimesh.load(path, force="mesh", process=True).is_watertight else "no"


def main():
    kardia, work = sys.argv[1], sys.argv[2]
    only = os.environ.get("ONLY")
    nmax = int(os.environ.get("NMAX", "400"))
    repeat = max(1, int(os.environ.get("REPEAT", "3")))
    # Shares of kardia's default tolerance (1% of the clip radius), finest last.
    scales = sorted((float(s) for s in os.environ.get("SCALES", "1").split()), reverse=True)
    rows = []
    for name, preset, _, radius, cut in SURFACES:
        if only and not re.search(only, name):
            continue
        n_start = 32
        for scale in scales:
            tolerance = scale * 0.01 * radius
            tag = f"{name}-{scale:g}"
            k_path = os.path.join(work, f"{tag}-kardia.stl")
            out, k_time, k_mem = timed(
                [kardia, "mesh", "--preset", *preset, "--tolerance", repr(tolerance), "--quiet", "-o", k_path]
            )
            k_tris = int(re.search(r"\((\d+) triangles", out).group(1))
            k_meshing = float(re.search(r"meshing ([\d.]+) s", out).group(1))
            k_haus, k_s2m, k_beyond = measure(kardia, preset, tolerance, k_path)
            # Where the clip sphere cuts the surface, the distances compared are the
            # surface→mesh ones, which sample the exact surface: a file carries no vertex
            # kinds, and scikit-image's cap vertices (interpolated, not on the sphere) would
            # count as surface vertices, its cap triangles as far from the surface. So too
            # where kardia's own estimate is capped by the search reach (samples with no
            # surface point found on the lines searched).
            by_s2m = cut or k_beyond > 0
            k_dist = k_s2m if by_s2m else k_haus
            print(
                f"{name} (tolerance {tolerance:.3g}): kardia {k_tris} triangles, meshing {k_meshing:.3f} s "
                f"(whole run {k_time:.2f} s), {k_mem:.0f} MB, distance {k_dist:.2e}",
                flush=True,
            )
            n = n_start
            while True:
                s_path = os.path.join(work, f"{tag}-skimage-{n}.stl")
                out, _, s_mem = timed([sys.executable, __file__, "--skimage", name, str(n), s_path])
                s = json.loads(out)
                s_haus, s_s2m, _ = measure(kardia, preset, tolerance, s_path)
                s_dist = s_s2m if by_s2m else s_haus
                print(
                    f"  skimage n={n}: {s['triangles']} triangles, {s['time']:.3f} s, {s_mem:.0f} MB, "
                    f"distance {s_dist:.2e}",
                    flush=True,
                )
                if s_dist <= k_dist or n >= nmax:
                    break
                n = min(nmax, int(n * 1.25))
            # A finer tolerance needs at least this grid.
            n_start = n
            # The times compared: medians of REPEAT runs of each, interleaved (the machine
            # is shared and noisy), the runs above counting as the first.
            k_times, s_times = [k_meshing], [s["time"]]
            for _ in range(repeat - 1):
                out, _, _ = timed(
                    [kardia, "mesh", "--preset", *preset, "--tolerance", repr(tolerance), "--quiet", "-o", k_path]
                )
                k_times.append(float(re.search(r"meshing ([\d.]+) s", out).group(1)))
                out, _, _ = timed([sys.executable, __file__, "--skimage", name, str(n), s_path])
                s_times.append(json.loads(out)["time"])
            k_meshing, s["time"] = statistics.median(k_times), statistics.median(s_times)
            print(f"  medians of {repeat}: kardia {k_meshing:.3f} s, skimage {s['time']:.3f} s", flush=True)
            rows.append(
                (
                    name + (" (surface→mesh)" if by_s2m else ""),
                    tolerance,
                    k_meshing,
                    k_time,
                    k_tris,
                    k_mem,
                    k_dist,
                    watertight(k_path),
                    n,
                    s["time"],
                    s["triangles"],
                    s_mem,
                    s_dist,
                    watertight(s_path),
                )
            )
    print()
    print(
        "| surface | tolerance | kardia meshing time | whole run | triangles | peak memory | distance | watertight "
        "| skimage grid | time | triangles | peak memory | distance | watertight "
        "| meshing time kardia/skimage | triangles kardia/skimage |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, tol, kmt, kt, ktr, km, kd, kw, n, st, stri, sm, sd, sw in rows:
        reached = "" if sd <= kd else " (not reached)"
        print(
            f"| {name} | {tol:.3g} | {kmt:.3f} s | {kt:.2f} s | {ktr} | {km:.0f} MB | {kd:.2e} | {kw} "
            f"| {n}³{reached} | {st:.3f} s | {stri} | {sm:.0f} MB | {sd:.2e} | {sw} "
            f"| {kmt / st:.2f} | {ktr / stri:.2f} |"
        )


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--skimage":
        skimage_mesh(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        main()
