"""Speed of the Python package, side by side with its references in one run
(not run by CI: timings belong to benchmarks, not tests).

1. ``sora.mie.efficiencies`` against miepython (with numba, when
   installed) on the two workloads of the Mie benchmark
   (crates/sora-mie/benches/sphere.rs): (a) 100 000 spheres, x log-spaced
   over 0.1-100, (b) 1 000 spheres, x over 100-10 000, m = 1.5+0.01i; and
   the largest relative difference between the two (miepython writes the
   index n - ik: it gets m.conjugate()), and the largest relative
   difference from the Rust crate (``sora mie --batch``, 17 digits).
2. ``sky.render`` of a 512 x 512 fisheye against ``sora render`` (its
   "rendered ... in X s": tables and pixels, without the PNG), both on a
   freshly built sky.

    pip install miepython numba          # in the environment with sora
    python benchmarks/benchmark.py [--cli target/release/sora] [--repeat 5]

Each timing is the median of --repeat runs after one warm-up (numba's
compilation is not counted).
"""

import argparse
import os
import pathlib
import re
import statistics
import subprocess
import tempfile
import time

import numpy as np

import sora


def median_seconds(function, repeat):
    function()  # warm-up: numba compiles, caches fill
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def rust_crate_efficiencies(cli, m, x):
    """The Rust crate's values through ``sora mie --batch`` (17 digits)."""
    with tempfile.TemporaryDirectory() as directory:
        path = pathlib.Path(directory) / "spheres.csv"
        path.write_text("m_re,m_im,x\n" + "".join(f"{m.real!r},{m.imag!r},{float(v)!r}\n" for v in x))
        output = subprocess.run([str(cli), "mie", "--batch", str(path)], check=True, capture_output=True, text=True).stdout
    return np.loadtxt(output.splitlines()[1:], delimiter=",")[:, 3:]


def mie_workloads(repeat, cli):
    # miepython compiles its kernels with numba only when asked to.
    os.environ.setdefault("MIEPYTHON_USE_JIT", "1")
    try:
        import miepython
    except ImportError:
        miepython = None
    # miepython compiles its kernels with numba when numba is installed.
    jit = "with numba" if getattr(miepython, "USE_JIT", False) else "without numba"
    m = 1.5 + 0.01j
    workloads = [
        ("a: 100000 spheres, x 0.1..100", np.logspace(np.log10(0.1), np.log10(100.0), 100_000)),
        ("b: 1000 spheres, x 100..10000", np.logspace(np.log10(100.0), np.log10(10_000.0), 1_000)),
    ]
    threads = sora.get_num_threads()
    print(f"Mie efficiencies, m = {m}; miepython {getattr(miepython, '__version__', 'not installed')} {jit}; sora on 1 and {threads} threads")
    print(f"{'workload':32} {'miepython s':>12} {'sora 1 thr s':>13} {'ratio':>7} {'sora all s':>11} {'ratio':>7} {'vs miepython':>13} {'vs Rust':>9}")
    for name, x in workloads:
        sora.set_num_threads(1)
        one = median_seconds(lambda: sora.mie.efficiencies(m, x), repeat)
        sora.set_num_threads(0)
        every = median_seconds(lambda: sora.mie.efficiencies(m, x), repeat)
        q = sora.mie.efficiencies(m, x)
        rust = "-"
        if pathlib.Path(cli).exists():
            table = rust_crate_efficiencies(cli, m, x)
            ours = np.stack([q.qext, q.qsca, q.qabs, q.qback, q.g], axis=1)
            rust = f"{np.max(np.abs(ours / table - 1)):9.1e}"
        if miepython is None:
            print(f"{name:32} {'-':>12} {one:13.4f} {'-':>7} {every:11.4f} {'-':>7} {'-':>13} {rust:>9}")
            continue
        reference = miepython.efficiencies_mx(m.conjugate(), x)
        theirs = median_seconds(lambda: miepython.efficiencies_mx(m.conjugate(), x), repeat)
        qext, qsca, qback, g = reference
        difference = max(
            np.max(np.abs(q.qext / qext - 1)),
            np.max(np.abs(q.qsca / qsca - 1)),
            np.max(np.abs(q.g / g - 1)),
        )
        print(f"{name:32} {theirs:12.4f} {one:13.4f} {theirs / one:7.1f} {every:11.4f} {theirs / every:7.1f} {difference:13.2e} {rust:>9}")


def render_against_cli(cli, repeat):
    atmosphere = sora.Atmosphere.preset("earth-clear")

    def python_render():
        sky = sora.Sky(atmosphere, sun_elevation_deg=30)
        started = time.perf_counter()
        sky.render(camera="fisheye", width=512)
        return time.perf_counter() - started

    def cli_render():
        with tempfile.TemporaryDirectory() as directory:
            result = subprocess.run(
                [str(cli), "render", "--preset", "earth-clear", "--sun-elevation", "30",
                 "--width", "512", "--height", "512", "-o", str(pathlib.Path(directory) / "sky.png")],
                check=True, capture_output=True, text=True,
            )
        return float(re.search(r"\) in ([0-9.]+) s", result.stderr).group(1))

    python_render(), cli_render()  # warm-up
    python_times, cli_times = [], []
    for _ in range(repeat):  # interleaved, so both see the same load
        python_times.append(python_render())
        cli_times.append(cli_render())
    p, c = statistics.median(python_times), statistics.median(cli_times)
    print(f"512 x 512 fisheye, earth-clear, sun 30 deg, all orders, {sora.get_num_threads()} threads:")
    print(f"  sky.render {p:.3f} s, sora render {c:.3f} s: Python / CLI = {p / c:.3f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    repository = pathlib.Path(__file__).resolve().parents[3]
    parser.add_argument("--cli", default=str(repository / "target" / "release" / "sora"))
    parser.add_argument("--repeat", type=int, default=5)
    arguments = parser.parse_args()
    mie_workloads(arguments.repeat, arguments.cli)
    if pathlib.Path(arguments.cli).exists():
        render_against_cli(arguments.cli, arguments.repeat)
    else:
        print(f"no CLI at {arguments.cli}: cargo build --release -p sora-cli for the render comparison")


if __name__ == "__main__":
    main()
