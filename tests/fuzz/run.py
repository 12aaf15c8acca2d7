"""``make fuzz``: run every harness of harnesses.txt for a bounded time and keep what it finds.

    python tests/fuzz/run.py [--seconds S] [--only NAME ...] [--jobs N]

For each harness: seeds are written afresh into build/fuzz/seeds/NAME (tests/fuzz/seeds.py,
from the procedural assets and the development data), the working corpus grows in
build/fuzz/corpus/NAME across runs, and libFuzzer (C++) or atheris (Python) runs for S seconds
(FUZZ_SECONDS, default 60) with a timeout per input of 1 s (C++) or 5 s (Python, whose
atheris instrumentation slows it several times; tests/python/test_fuzz_regressions.py holds
the uninstrumented readers to 1 s) and a 2 GiB memory limit. Crash, leak,
timeout and out-of-memory inputs are moved into tests/fuzz/crashes/NAME/, where `make test`
replays them. Prints one Markdown row per harness (executions, coverage, corpus, crashes) and
exits 1 when any harness found something.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import resource
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

FUZZ_DIR = Path(__file__).resolve().parent
ROOT = FUZZ_DIR.parents[1]
BUILD = ROOT / "build" / "fuzz"
ARTIFACT_KINDS = ("crash", "leak", "timeout", "oom", "slow-unit")


@dataclass
class Harness:
    name: str
    language: str
    seeds: str
    dictionary: str | None


def load_registry(path: Path = FUZZ_DIR / "harnesses.txt") -> list[Harness]:
    """The harnesses listed in harnesses.txt, in file order."""
    harnesses = []
    for line in path.read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if words:
            harnesses.append(Harness(words[0], words[1], words[2], words[3] if len(words) > 3 else None))
    return harnesses


def command(
    harness: Harness, seconds: int, corpus: Path, seeds: Path, artifacts: Path, timeout: int | None = None
) -> list[str]:
    flags = [
        f"-max_total_time={seconds}",
        f"-timeout={timeout or (1 if harness.language == 'cpp' else 5)}",
        "-rss_limit_mb=2048",
        "-print_final_stats=1",
        f"-artifact_prefix={artifacts}/",
        f"-max_len={65536 if harness.language == 'cpp' else 131072}",
    ]
    if harness.dictionary:
        flags.append(f"-dict={FUZZ_DIR / 'dicts' / harness.dictionary}")
    if harness.language == "cpp":
        return [str(BUILD / "tests" / "fuzz" / "cpp" / f"animlod_fuzz_{harness.name}"), *flags, str(corpus), str(seeds)]
    return [sys.executable, str(FUZZ_DIR / "run_atheris.py"), harness.name, *flags, str(corpus), str(seeds)]


def run_one(harness: Harness, seconds: int, timeout: int | None = None) -> dict:
    sys.path.insert(0, str(FUZZ_DIR))
    from seeds import write_seeds

    seeds, corpus = BUILD / "seeds" / harness.name, BUILD / "corpus" / harness.name
    artifacts = BUILD / "artifacts" / harness.name
    seed_count = write_seeds(harness.seeds, seeds)
    corpus.mkdir(parents=True, exist_ok=True)
    shutil.rmtree(artifacts, ignore_errors=True)
    artifacts.mkdir(parents=True)
    log = BUILD / "logs" / f"{harness.name}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    sanitizers = {"ASAN_OPTIONS": "detect_leaks=1:allocator_may_return_null=1", "UBSAN_OPTIONS": "print_stacktrace=1"}
    env = dict(os.environ, **sanitizers)
    with open(log, "w") as output:
        code = subprocess.run(command(harness, seconds, corpus, seeds, artifacts, timeout), stdout=output,
                              stderr=subprocess.STDOUT, env=env, cwd=ROOT).returncode  # fmt: skip
    text = log.read_text(errors="replace")
    found = _keep_artifacts(harness.name, artifacts)
    stats = {key: int(value) for key, value in re.findall(r"stat::(\w+):\s+(\d+)", text)}
    done = re.findall(r"#(\d+)\s+(?:DONE|INITED|NEW|REDUCE|pulse)\s+cov: (\d+) ft: (\d+) corp: (\d+)", text)
    executions = stats.get("number_of_executed_units", int(done[-1][0]) if done else 0)
    return {
        "harness": harness.name,
        "language": harness.language,
        "seconds": round(time.monotonic() - start),
        "seeds": seed_count,
        "executions": executions,
        "coverage": int(done[-1][1]) if done else 0,
        "features": int(done[-1][2]) if done else 0,
        "corpus": int(done[-1][3]) if done else 0,
        "found": found,
        "exit": code,
        "log": log,
    }


def replay_corpus(harness: Harness) -> list[Path]:
    """Every input of the harness's corpus once, at libFuzzer's default timeout for C++ (1 s):
    the check of a run made with a longer --timeout. Returns what it found (kept as artifacts)."""
    corpus, artifacts = BUILD / "corpus" / harness.name, BUILD / "artifacts" / harness.name
    shutil.rmtree(artifacts, ignore_errors=True)
    artifacts.mkdir(parents=True)
    binary = BUILD / "tests" / "fuzz" / "cpp" / f"animlod_fuzz_{harness.name}"
    flags = ["-runs=0", "-timeout=1", "-rss_limit_mb=2048", f"-artifact_prefix={artifacts}/", "-max_len=65536"]
    log = BUILD / "logs" / f"{harness.name}.replay.log"
    sanitizers = {"ASAN_OPTIONS": "detect_leaks=1:allocator_may_return_null=1", "UBSAN_OPTIONS": "print_stacktrace=1"}
    env = dict(os.environ, **sanitizers)
    with open(log, "w") as output:
        subprocess.run([str(binary), *flags, str(corpus)], stdout=output, stderr=subprocess.STDOUT, env=env, cwd=ROOT)
    # The timeout is wall time, so a starved process (nice 19 beside builds) can exceed it on a
    # quick input: a timeout counts only when the input alone takes over 1 s of CPU.
    for path in sorted(artifacts.glob("timeout-*")):
        seconds = _cpu_seconds([str(binary), "-runs=1", "-timeout=600", str(path)], env)
        if seconds < 1.0:
            print(f"{harness.name}: {path.name} took {seconds:.2f} s of CPU alone: a starved run's wall-time timeout")
            path.unlink()
    found = _keep_artifacts(harness.name, artifacts)
    names = ", ".join(p.name for p in found) or "nothing found"
    print(f"{harness.name}: corpus replayed at -timeout=1 ({log}): {names}")
    return found


def _cpu_seconds(argv: list[str], env: dict[str, str]) -> float:
    """User + system CPU seconds of one run of ``argv``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, cwd=ROOT)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _keep_artifacts(name: str, artifacts: Path) -> list[Path]:
    """Move libFuzzer's artifacts into tests/fuzz/crashes/NAME/, named by kind and content."""
    kept = []
    for path in sorted(artifacts.iterdir()):
        kind = next((k for k in ARTIFACT_KINDS if path.name.startswith(k)), None)
        if kind is None:
            continue
        data = path.read_bytes()
        target = FUZZ_DIR / "crashes" / name / f"{kind}-{hashlib.sha1(data).hexdigest()[:16]}"
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
        path.unlink()
        kept.append(target)
    return kept


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=int, default=int(os.environ.get("FUZZ_SECONDS", "60")))
    parser.add_argument("--only", nargs="+", help="harness names (default: all)")
    parser.add_argument("--jobs", type=int, default=1, help="harnesses run side by side (at most 2 here)")
    parser.add_argument(
        "--fail-on", default=",".join(ARTIFACT_KINDS),
        help="artifact kinds that fail the run (CI's smoke leaves out timeouts, which a loaded machine can cause)",
    )  # fmt: skip
    parser.add_argument(
        "--timeout", type=int,
        help="seconds per input before libFuzzer calls it a timeout (default 1 for C++, 5 for Python); "
        "libFuzzer counts wall time, so a run at nice 19 on a loaded machine needs more, and the corpus "
        "is then replayed at the default (--replay-corpus)",
    )  # fmt: skip
    parser.add_argument(
        "--replay-corpus", action="store_true",
        help="after fuzzing, run every corpus input once with the default timeout (C++ harnesses)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    harnesses = [h for h in load_registry() if not args.only or h.name in args.only]
    unknown = set(args.only or ()) - {h.name for h in harnesses}
    if unknown:
        parser.error(f"no harness named {', '.join(sorted(unknown))} in harnesses.txt")
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(lambda h: run_one(h, args.seconds, args.timeout), harnesses))
    if args.replay_corpus:
        for r in rows:
            if r["language"] == "cpp":
                r["found"] += replay_corpus(next(h for h in harnesses if h.name == r["harness"]))
    print("| harness | language | seconds | seeds | executions | exec/s | coverage (edges) | features | corpus "
          "| found |")  # fmt: skip
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---|")
    for r in rows:
        rate = r["executions"] // max(r["seconds"], 1)
        found = ", ".join(p.name for p in r["found"]) or "none"
        print(f"| {r['harness']} | {r['language']} | {r['seconds']} | {r['seeds']} | {r['executions']} | {rate} | "
              f"{r['coverage']} | {r['features']} | {r['corpus']} | {found} |")  # fmt: skip
    fatal = tuple(kind for kind in args.fail_on.split(",") if kind)
    # A harness fails on a fatal artifact, or on a non-zero exit that left no artifact at all.
    failed = [r for r in rows if any(p.name.startswith(fatal) for p in r["found"]) or (r["exit"] and not r["found"])]
    for r in failed:
        print(f"\n{r['harness']}: exit {r['exit']}, log {r['log']}", file=sys.stderr)
        for path in r["found"]:
            data = path.read_bytes()
            print(f"  saved {path.relative_to(ROOT)} ({len(data)} bytes): replayed by make test", file=sys.stderr)
            if len(data) <= 4096:  # a CI log keeps a small input even when the clone is gone
                print(f"  hex: {data.hex()}", file=sys.stderr)
        print("  " + "\n  ".join(r["log"].read_text(errors="replace").splitlines()[-25:]), file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
