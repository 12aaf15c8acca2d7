"""Progress of a batch: one bar overall and one per running asset (tqdm, on a terminal only).

The runner calls :class:`BatchProgress` from two threads: ``asset_event`` from the Dask
client's event loop (progress events the workers send), the rest from the main thread.
"""

from __future__ import annotations

import threading


class BatchProgress:
    """The runner's progress interface; this base class shows nothing."""

    def start(self, to_run: int, skipped: int) -> None:
        """``to_run`` assets are submitted; ``skipped`` were unchanged since the last run."""

    def asset_event(self, name: str, fraction: float | None, message: str) -> None:
        """Asset ``name`` reports ``fraction`` done (None: unknown) and what it is doing."""

    def asset_done(self, record: dict) -> None:
        """Asset ``record["name"]`` finished (``record["status"]`` "ok" or "failed")."""

    def close(self) -> None:
        """The batch is over."""


class TqdmProgress(BatchProgress):
    """tqdm bars: position 0 counts assets, the lines below follow the running ones (at most
    ``slots``, the number of workers). When stderr is not a terminal, one line per finished
    asset on stdout instead."""

    def __init__(self, slots: int = 4) -> None:
        self.slots = max(1, slots)
        self.lock = threading.Lock()
        self.overall = None
        self.bars: dict[str, tuple[object, int]] = {}  # name -> (bar, its line)
        self.free: list[int] = []
        self.done = 0
        self.total = 0

    def start(self, to_run: int, skipped: int) -> None:
        from tqdm import tqdm

        self._tqdm = tqdm
        with self.lock:
            self.total = to_run
            self.overall = tqdm(total=to_run, desc="assets", unit="asset", position=0, disable=None, dynamic_ncols=True)
            if skipped:
                self.overall.set_postfix_str(f"{skipped} unchanged, skipped")
            self.free = list(range(1, self.slots + 1))

    def asset_event(self, name: str, fraction: float | None, message: str) -> None:
        with self.lock:
            if self.overall is None or self.overall.disable:
                return
            if name not in self.bars:
                if not self.free:
                    return
                line = self.free.pop(0)
                bar = self._tqdm(
                    total=100, desc=name, position=line, leave=False, disable=None, dynamic_ncols=True,
                    bar_format="{desc}: {percentage:3.0f}%|{bar}| {postfix}",
                )  # fmt: skip
                self.bars[name] = (bar, line)
            bar = self.bars[name][0]
            if fraction is not None:
                bar.update(max(0.0, min(100.0, 100.0 * fraction)) - bar.n)
            bar.set_postfix_str(message[:60], refresh=True)

    def asset_done(self, record: dict) -> None:
        with self.lock:
            entry = self.bars.pop(record["name"], None)
            if entry is not None:
                entry[0].close()
                self.free.append(entry[1])
                self.free.sort()
            self.done += 1
            if self.overall is not None:
                self.overall.update(1)
                error = record.get("error") or {}
                if not self.overall.disable:
                    if record["status"] != "ok":
                        self.overall.write(f"failed {record['name']}: {error.get('reason', '?')}")
                    return
                # No terminal (a log file, a farm's job output): one line per asset instead of bars.
                seconds = record.get("seconds")
                took = f" in {seconds:.1f} s" if isinstance(seconds, (int, float)) else ""
                status = "ok" if record["status"] == "ok" else f"failed: {error.get('reason', '?')}"
                print(f"[{self.done}/{self.total}] {record['name']}: {status}{took}", flush=True)

    def close(self) -> None:
        with self.lock:
            for bar, _ in self.bars.values():
                bar.close()
            self.bars.clear()
            if self.overall is not None:
                self.overall.close()
