#!/usr/bin/env python3
"""A live web view kept open in a headless browser: does the tab last? Numbers, not a test.

Usage:  .venv/bin/python scripts/live_view_soak.py [--minutes 30] [--domain-id 42] [--out DIR]
                                                  [--driver twist|operator] [--width 1024]
                                                  [--height 640]

Starts on --domain-id (localhost only) the stack docs/live_view.md starts by hand, as console
scripts from .venv/bin: ``rns_rerun_logger`` with ``sink:=serve`` (free gRPC and web ports),
``rns_simulator``, ``rns_controller`` and an operator. ``--driver twist`` (default): this process
streams TwistStamped on /cmd_twist at :data:`TWIST_RATE` (world frame, :data:`SPEED` rad/s about
world z, reversed every :data:`HALF_SWING` s: the camera swings back and forth for as long as the
soak runs); ``--driver operator``: ``rns_operator`` plays the satellite_observation scenario (it
ends after about 25 s, then the arm stands still).

Then it opens the URL the logger prints (with its ``?url=``) in Debian's Chromium, headless,
software WebGL, a fresh profile, driven by playwright, and keeps the page open for --minutes.
Every minute it prints whether the page is alive (no crash, no :data:`DEATH_TEXTS` in the
console), the viewer's WebAssembly memory (what rerun's 2.3 GiB limit is about), the JS heap
(CDP ``Performance.getMetrics``), the RSS of the browser's renderer and GPU processes and of the
logger (its gRPC server keeps the run for late viewers), and the load average. At the end:
a screenshot and ``soak.json`` in --out. Exit code 0: the page lived to the end; 1: it died or
the stack stopped; 2: set-up error (no chromium, no playwright, a domain in use).

Needs ``apt-get install -y chromium`` and ``.venv/bin/pip install playwright==1.65.2`` (no
browser download: Debian's /usr/bin/chromium is used). CPU: the software rasterizer takes most
of a core; the stack another.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path

#: Chromium binary (Debian's package).
CHROMIUM = "/usr/bin/chromium"
#: Browser flags: headless, software WebGL (SwiftShader: no GPU here), no first-run or
#: background traffic, nothing kept between runs (a fresh --user-data-dir is added).
CHROMIUM_ARGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)
#: Console texts that mean the viewer died (a WebAssembly trap after running out of memory).
DEATH_TEXTS = ("RuntimeError: unreachable", "memory limit", "panicked", "out of memory")
#: Twist stream of the scripted operator: rate [Hz], speed [rad/s], time per direction [s].
TWIST_RATE = 50.0
SPEED = 0.05
HALF_SWING = 20.0
#: Longest wait for the logger to print its URL, and for the page to load [s].
START_TIMEOUT = 120.0
#: Time between two reports [s].
REPORT_PERIOD = 60.0
#: Longest wait for the final screenshot: software rendering draws a frame in seconds [ms].
SCREENSHOT_TIMEOUT = 180_000
#: Captures every WebAssembly memory the page creates, so its size can be read.
WASM_MEMORY_PROBE = """
(() => {
  const memories = [];
  window.__soakWasmMemories = memories;
  const keep = (result) => {
    const instance = result && (result.instance || result);
    try {
      for (const value of Object.values(instance.exports || {})) {
        if (value instanceof WebAssembly.Memory) memories.push(value);
      }
    } catch (error) {}
    return result;
  };
  const instantiate = WebAssembly.instantiate;
  WebAssembly.instantiate = function (...args) {
    return instantiate.apply(this, args).then(keep);
  };
  const streaming = WebAssembly.instantiateStreaming;
  if (streaming) {
    WebAssembly.instantiateStreaming = function (...args) {
      return streaming.apply(this, args).then(keep);
    };
  }
})();
"""
MIB = 1 << 20


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=30.0, help="how long the page stays open")
    parser.add_argument(
        "--domain-id",
        type=int,
        default=int(os.environ.get("ROS_DOMAIN_ID", "42")),
        help="ROS domain of the stack (default: ROS_DOMAIN_ID, else 42)",
    )
    parser.add_argument("--out", type=Path, default=Path("live_view_soak"), help="results folder")
    parser.add_argument("--driver", choices=("twist", "operator"), default="twist")
    parser.add_argument("--width", type=int, default=1024, help="browser viewport [px]")
    parser.add_argument("--height", type=int, default=640, help="browser viewport [px]")
    args = parser.parse_args(argv)
    if not args.minutes > 0:
        parser.error(f"--minutes must be > 0, got {args.minutes}")
    return args


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def rss_mib(pid: int) -> float | None:
    """Resident memory of process ``pid`` [MiB], None when it is gone."""
    with contextlib.suppress(OSError, ValueError):
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return None


def _processes() -> dict[int, tuple[int, str, float]]:
    """{pid: (parent pid, command line, CPU time used [s])} of every readable process."""
    table = {}
    tick = os.sysconf("SC_CLK_TCK")
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            argv = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except OSError:
            continue
        cpu = (int(stat[11]) + int(stat[12])) / tick  # utime + stime
        table[int(entry.name)] = (int(stat[1]), argv.decode(errors="replace"), cpu)
    return table


def browser_usage(profile: str) -> dict[str, tuple[float, float]]:
    """{Chromium process type (browser, renderer, gpu-process, ...): (RSS [MiB], CPU time [s])}
    summed over the browser started with this user-data-dir and its descendants (Chromium
    rewrites its command lines into one string: the type is found in it)."""
    table = _processes()
    family = {pid for pid, (_, line, _) in table.items() if profile in line}
    while children := {pid for pid, (up, _, _) in table.items() if up in family} - family:
        family |= children
    totals: dict[str, tuple[float, float]] = {}
    for pid in family:
        _, line, cpu = table[pid]
        found = re.search(r"--type=(\S+)", line)
        kind = found.group(1) if found else "browser"
        memory = rss_mib(pid) or 0.0
        rss, used = totals.get(kind, (0.0, 0.0))
        totals[kind] = (rss + memory, used + cpu)
    return totals


def cpu_seconds(pid: int) -> float | None:
    """CPU time process ``pid`` used so far [s], None when it is gone."""
    entry = _processes().get(pid)
    return None if entry is None else entry[2]


class TwistDriver:
    """The scripted operator: TwistStamped on /cmd_twist from a thread (see the module doc)."""

    def __init__(self, node) -> None:
        from geometry_msgs.msg import TwistStamped

        self._message = TwistStamped
        self._node = node
        self._publisher = node.create_publisher(TwistStamped, "cmd_twist", 10)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.sent = 0

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def _run(self) -> None:
        begin = time.monotonic()
        while not self._stop.is_set():
            elapsed = time.monotonic() - begin
            msg = self._message()
            msg.header.stamp = self._node.get_clock().now().to_msg()
            msg.header.frame_id = "world"
            forward = int(elapsed // HALF_SWING) % 2 == 0
            msg.twist.angular.z = SPEED if forward else -SPEED
            self._publisher.publish(msg)
            self.sent += 1
            self._stop.wait(max(begin + self.sent / TWIST_RATE - time.monotonic(), 0.0))


class PageWatch:
    """What the page said and how much memory it holds."""

    def __init__(self, page, cdp) -> None:
        self.page, self.cdp = page, cdp
        self.deaths: list[str] = []  # console texts of DEATH_TEXTS, and crashes
        self.errors = 0  # console errors seen
        self.first_error: str | None = None
        page.on("console", self._on_console)
        page.on("pageerror", lambda error: self._on_text(f"pageerror: {error}"))
        page.on("crash", lambda _page: self.deaths.append("the page crashed"))

    def _on_console(self, message) -> None:
        if message.type == "error":
            self.errors += 1
            self.first_error = self.first_error or message.text[:300]
        self._on_text(message.text)

    def _on_text(self, text: str) -> None:
        if any(death.lower() in text.lower() for death in DEATH_TEXTS):
            self.deaths.append(" ".join(text.split())[:300])

    @property
    def alive(self) -> bool:
        return not self.deaths

    def memory(self) -> dict[str, float | None]:
        """WebAssembly memory and JS heap [MiB] (None when the page does not answer)."""
        figures: dict[str, float | None] = {"wasm": None, "js_heap_used": None, "js_heap": None}
        with contextlib.suppress(Exception):
            sizes = self.page.evaluate(
                "() => (window.__soakWasmMemories || []).map(m => m.buffer.byteLength)"
            )
            figures["wasm"] = sum(sizes) / MIB if sizes else None
        with contextlib.suppress(Exception):
            metrics = {
                m["name"]: m["value"] for m in self.cdp.send("Performance.getMetrics")["metrics"]
            }
            figures["js_heap_used"] = metrics.get("JSHeapUsedSize", 0.0) / MIB
            figures["js_heap"] = metrics.get("JSHeapTotalSize", 0.0) / MIB
        return figures


def logger_url(stack, process, timeout: float) -> str:
    """The web viewer URL (with ``?url=``) the logger prints once its sink is open."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = re.search(r"open (http://\S+) in a browser", stack.output(process))
        if found:
            return found.group(1)
        if process.poll() is not None:
            break
        time.sleep(0.2)
    raise RuntimeError(f"rns_rerun_logger printed no URL{stack.exit_report()}")


def fmt(value: float | None, unit: str = "MiB") -> str:
    return "-" if value is None else f"{value:.0f} {unit}"


def soak(args: argparse.Namespace) -> int:
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        print("needs playwright: .venv/bin/pip install playwright==1.65.2", file=sys.stderr)
        return 2
    if not Path(CHROMIUM).exists():
        print(f"needs {CHROMIUM}: apt-get install -y chromium", file=sys.stderr)
        return 2
    from rns_ros.harness import CLAIM_PREFIX, DomainInUseError, ProcessStack, claim_domain

    args.out.mkdir(parents=True, exist_ok=True)
    try:
        claim = claim_domain(args.domain_id, f"{CLAIM_PREFIX}_live_view_soak_{os.getpid()}")
    except DomainInUseError as exc:
        print(exc, file=sys.stderr)
        return 2
    rows: list[dict] = []
    result: dict = {"minutes": args.minutes, "driver": args.driver, "rows": rows}
    driver = None
    grpc_port, web_port = free_port(), free_port()
    with claim, ProcessStack(args.domain_id) as stack, tempfile.TemporaryDirectory() as profile:
        logger = stack.start(
            "rns_rerun_logger",
            {"sink": "serve", "grpc_port": grpc_port, "web_port": web_port},
        )
        url = logger_url(stack, logger, START_TIMEOUT)
        stack.start("rns_simulator")
        stack.start("rns_controller")
        if args.driver == "operator":
            stack.start("rns_operator", {"scenario": "satellite_observation"})
        else:
            driver = TwistDriver(claim.probe("live_view_soak_operator"))
            driver.start()
        print(f"stack on domain {args.domain_id}; viewer {url}", flush=True)
        result["url"] = url
        with sync_playwright() as playwright:
            context = playwright.chromium.launch_persistent_context(
                profile,
                executable_path=CHROMIUM,
                headless=True,
                args=list(CHROMIUM_ARGS),
                viewport={"width": args.width, "height": args.height},
            )
            try:
                page = context.pages[0] if context.pages else context.new_page()
                page.add_init_script(WASM_MEMORY_PROBE)
                cdp = context.new_cdp_session(page)
                cdp.send("Performance.enable")
                watch = PageWatch(page, cdp)
                page.goto(url, timeout=START_TIMEOUT * 1000)
                opened = time.monotonic()
                deadline = opened + args.minutes * 60.0
                next_report = opened + min(REPORT_PERIOD, args.minutes * 60.0)

                def report(now: float) -> None:
                    row = {"minute": round((now - opened) / 60.0, 2), "alive": watch.alive}
                    row |= watch.memory()
                    usage = browser_usage(profile)
                    for kind, name in (("renderer", "renderer"), ("gpu-process", "gpu")):
                        row[f"{name}_rss"], row[f"{name}_cpu_s"] = usage.get(kind, (None,) * 2)
                    row["logger_rss"] = rss_mib(logger.pid)
                    row["logger_cpu_s"] = cpu_seconds(logger.pid)
                    row["load"] = os.getloadavg()[0]
                    row["console_errors"] = watch.errors
                    rows.append(row)
                    print(
                        f"minute {row['minute']:5.1f}: "
                        f"{'alive' if row['alive'] else 'DEAD'}, wasm {fmt(row['wasm'])}, "
                        f"JS heap {fmt(row['js_heap_used'])} of {fmt(row['js_heap'])}, "
                        f"renderer {fmt(row['renderer_rss'])} "
                        f"({fmt(row['renderer_cpu_s'], 's')} CPU), "
                        f"gpu {fmt(row['gpu_rss'])} ({fmt(row['gpu_cpu_s'], 's')} CPU), "
                        f"logger {fmt(row['logger_rss'])} "
                        f"({fmt(row['logger_cpu_s'], 's')} CPU), load {row['load']:.1f}",
                        flush=True,
                    )

                while watch.alive and not stack.exited():
                    page.wait_for_timeout(1000)  # console events arrive while waiting
                    now = time.monotonic()
                    if now >= next_report or now >= deadline:
                        report(now)
                        next_report += REPORT_PERIOD
                    if now >= deadline:
                        break
                else:  # the page died or the stack stopped: the figures at that moment
                    report(time.monotonic())
                result["open_minutes"] = round((time.monotonic() - opened) / 60.0, 2)
                shot = args.out / "live_view_soak.png"
                with contextlib.suppress(Exception):
                    page.screenshot(path=str(shot), timeout=SCREENSHOT_TIMEOUT)
                    result["screenshot"] = str(shot)
                result["alive"] = watch.alive
                result["deaths"] = watch.deaths
                result["first_console_error"] = watch.first_error
            finally:
                context.close()
        if driver is not None:
            driver.stop()
            result["twists_sent"] = driver.sent
        result["stack_exited"] = stack.exit_report()
        result["stack_problems"] = stack.problems()
    (args.out / "soak.json").write_text(json.dumps(result, indent=2))
    lived = result.get("alive") and not result["stack_exited"]
    print(
        f"{'the page lived' if lived else 'FAILED'}: open {result.get('open_minutes')} min"
        f"{'; ' + '; '.join(result.get('deaths') or []) if result.get('deaths') else ''}"
        f"{result['stack_exited']}; results in {args.out}",
        flush=True,
    )
    return 0 if lived else 1


def main(argv: list[str] | None = None) -> int:
    try:
        return soak(parse_args(argv))
    except RuntimeError as exc:  # the stack did not come up
        print(f"live_view_soak: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
