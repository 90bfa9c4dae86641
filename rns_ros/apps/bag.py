"""``rns_bag``: the part of ``ros2 bag`` a teleoperation session needs, for rclpy alone.

``rns_bag record [-o DIR] (-a | TOPIC ...) [--max-bag-size BYTES] [--max-bag-duration S]``
records a rosbag2 folder as ``ros2 bag record -s mcap`` does (``DIR/metadata.yaml`` and
``DIR/DIR_0.mcap``, split by size or duration) until Ctrl-C or SIGTERM, which close it whole.
``rns_bag info DIR|FILE`` prints what ``ros2 bag info`` prints. ``rns_bag play DIR|FILE
[--rate R] [--clock [HZ]] [--loop] [--topics T ...] [--delay S]`` publishes the messages again
with their timing and QoS. Like ``ros2``, it joins the domain of its environment
(``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE``). See docs/bag.md.

Exit codes: 0 when done (Ctrl-C included), 1 when the bag could not be written whole (said in
one line, what was written removed), 2 with one line ``rns_bag: <problem>`` for bad arguments,
a path that is not a bag, a type that is not installed.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from datetime import datetime
from pathlib import Path

from rns_ros.bag import Bag, BagError, BagWriter, open_bag
from rns_ros.bag.metadata import NO_START
from rns_ros.cli import (
    OneLineParser,
    check_domain_id_environment,
    output_folder_problem,
    raise_on_sigterm,
    run_main,
    signals_held,
)
from rns_ros.core import ConfigError

PROGRAM = "rns_bag"
#: ros2 bag play's /clock rate when --clock is given without one [Hz].
DEFAULT_CLOCK_HZ = 40.0
#: Column of the values in ``info`` (ros2 bag info's).
INDENT = 19


def _number(kind: type, what: str):
    def convert(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a number, got {text!r}") from None
        if isinstance(value, float) and not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{what} must be finite, got {text!r}")
        return value

    return convert


def parser() -> OneLineParser:
    top = OneLineParser(
        prog=PROGRAM,
        description="Record, describe and play rosbag2 bags (MCAP) like ros2 bag, with rclpy "
        "alone. The domain comes from ROS_DOMAIN_ID, as for ros2.",
    )
    verbs = top.add_subparsers(dest="verb", metavar="{record,info,play}")
    verbs.required = True

    record = verbs.add_parser("record", help="record topics into a new bag folder")
    record.add_argument("topics", nargs="*", metavar="TOPIC", help="topics to record")
    record.add_argument("-a", "--all", action="store_true", help="record every topic")
    record.add_argument(
        "-o", "--output", type=Path, default=None,
        help="the bag folder to make (default: rosbag2_YYYY_MM_DD-HH_MM_SS)",
    )  # fmt: skip
    record.add_argument(
        "-s", "--storage", default="mcap", choices=["mcap"], help="storage (mcap only)"
    )
    record.add_argument(
        "-b", "--max-bag-size", type=_number(int, "--max-bag-size"), default=0,
        help="split when a file reaches this many bytes (0: never; else >= 1024)",
    )  # fmt: skip
    record.add_argument(
        "-d", "--max-bag-duration", type=_number(float, "--max-bag-duration"), default=0.0,
        help="split when a file spans more than this [s] (0: never)",
    )  # fmt: skip
    record.add_argument(
        "--include-hidden-topics", action="store_true", help="with -a, hidden topics too"
    )

    info = verbs.add_parser("info", help="describe a bag as ros2 bag info does")
    info.add_argument("bag", type=Path, help="bag folder or MCAP file")

    play = verbs.add_parser("play", help="publish a bag's messages again")
    play.add_argument("bag", type=Path, help="bag folder or MCAP file")
    play.add_argument(
        "-r", "--rate", type=_number(float, "--rate"), default=1.0, help="playback speed (> 0)"
    )
    play.add_argument(
        "--clock", type=_number(float, "--clock"), nargs="?", const=DEFAULT_CLOCK_HZ, default=0.0,
        metavar="HZ", help=f"publish /clock at HZ (default {DEFAULT_CLOCK_HZ:g}) with bag time",
    )  # fmt: skip
    play.add_argument("-l", "--loop", action="store_true", help="play again and again")
    play.add_argument("--topics", nargs="+", default=None, help="only these topics")
    play.add_argument(
        "-d", "--delay", type=_number(float, "--delay"), default=0.0,
        help="wait this long before playing (each loop) [s]",
    )  # fmt: skip
    return top


def main(argv: list[str] | None = None) -> int:
    """Exit code 0 (also after Ctrl-C), 1 when the bag was not written whole, 2 with one line
    on stderr for bad arguments or input."""
    return run_main(PROGRAM, lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    args = parser().parse_args(argv)
    if args.verb == "info":
        print(format_info(open_bag(args.bag)))
        return 0
    if args.verb == "record":
        return _record(args)
    return _play(args)


# --- info ---------------------------------------------------------------------------------------
def format_size(size: int) -> str:
    """Bytes as ros2 bag info writes them: ``812 B``, ``24.4 KiB``, ``3.1 MiB``."""
    value, units = float(size), ("B", "KiB", "MiB", "GiB", "TiB")
    index = 0
    while value >= 1024 and index < len(units) - 1:
        value /= 1024
        index += 1
    return f"{value:.0f} {units[0]}" if index == 0 else f"{value:.1f} {units[index]}"


def _seconds(nanoseconds: int) -> str:
    return f"{nanoseconds // 1_000_000_000}.{nanoseconds % 1_000_000_000:09d}"


def _time_point(nanoseconds: int) -> str:
    moment = datetime.fromtimestamp(nanoseconds // 1_000_000_000)
    date = f"{moment:%b} {moment.day:2d} {moment:%Y}"
    return f"{date} {moment:%H:%M:%S}.{nanoseconds % 1_000_000_000:09d} ({_seconds(nanoseconds)})"


def _column(label: str, values: list[str]) -> list[str]:
    head = f"{label:<{INDENT}}"
    if not values:
        return [head]
    return [head + values[0]] + [" " * INDENT + value for value in values[1:]]


def format_info(bag: Bag) -> str:
    """What ``ros2 bag info`` prints of ``bag``: files, size, storage, distribution, duration,
    start and end (local time, nanoseconds), messages, and one line per topic with its type,
    count and serialization format; services (never recorded here): 0."""
    meta = bag.metadata
    counted = meta.message_count > 0 and meta.starting_time_ns != NO_START
    lines = [""]
    lines += _column("Files:", meta.relative_file_paths if bag.path.is_dir() else [bag.path.name])
    lines += _column("Bag size:", [format_size(meta.bag_size)])
    lines += _column("Storage id:", [meta.storage_identifier])
    lines += _column("ROS Distro:", [meta.ros_distro or "unknown"])
    lines += _column("Duration:", [f"{_seconds(meta.duration_ns if counted else 0)}s"])
    lines += _column("Start:", [_time_point(meta.starting_time_ns) if counted else "-"])
    lines += _column("End:", [_time_point(meta.end_ns) if counted else "-"])
    lines += _column("Messages:", [str(meta.message_count)])
    lines += _column(
        "Topic information:",
        [
            f"Topic: {topic.name} | Type: {topic.type} | Count: {topic.message_count} | "
            f"Serialization Format: {topic.serialization_format}"
            for topic in meta.topics
        ],
    )
    lines += _column("Service:", ["0"])
    lines.append("Service information: ")
    return "\n".join(lines)


# --- record -------------------------------------------------------------------------------------
def _record(args: argparse.Namespace) -> int:
    if args.all and args.topics:
        raise ConfigError("give topics or -a, not both (see rns_bag record --help)")
    if not args.all and not args.topics:
        raise ConfigError("give the topics to record, or -a for all (see rns_bag record --help)")
    output = args.output or Path(datetime.now().strftime("rosbag2_%Y_%m_%d-%H_%M_%S"))
    if output.exists():
        raise BagError(f"output folder {output} already exists")
    if problem := output_folder_problem(output):
        raise BagError(f"output folder {output} {problem}")
    check_domain_id_environment()
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    from rns_ros.bag.recorder import Recorder
    from rns_ros.resources import apply_loopback_profile

    writer = BagWriter(
        output, max_bag_size=args.max_bag_size, max_bag_duration=args.max_bag_duration
    )
    recorder = None
    context = rclpy.Context()
    raise_on_sigterm()  # SIGTERM closes the bag as Ctrl-C does
    try:
        apply_loopback_profile()
        rclpy.init(args=[PROGRAM], context=context, signal_handler_options=SignalHandlerOptions.NO)
        recorder = Recorder(
            writer, None if args.all else args.topics,
            include_hidden=args.include_hidden_topics, context=context,
            say=lambda line: print(line, flush=True),
        )  # fmt: skip
        print(f"rns_bag: recording to {output} (Ctrl-C stops)", flush=True)
        recorder.spin()
    except KeyboardInterrupt:
        pass
    finally:
        with signals_held():
            if recorder is not None:
                recorder.close()
            path = writer.close()
            rclpy.try_shutdown(context=context)
    if path is None:
        print(f"rns_bag: {writer.problem}", file=sys.stderr)
        return 1
    meta = writer.metadata
    print(
        f"rns_bag: {meta.message_count} messages on {len(meta.topics)} topics in "
        f"{len(meta.files)} file(s): {path}"
    )
    return 0


# --- play ---------------------------------------------------------------------------------------
def _play(args: argparse.Namespace) -> int:
    from rns_ros.bag.player import check_rate, message_classes

    check_rate(args.rate)
    if args.clock:
        check_rate(args.clock, "--clock")
    if args.delay < 0:
        raise ConfigError(f"--delay must be >= 0 s, got {args.delay}")
    bag = open_bag(args.bag)
    message_classes(bag, args.topics)  # before joining the domain
    check_domain_id_environment()
    import rclpy
    from rclpy.signals import SignalHandlerOptions

    from rns_ros.bag.player import Player
    from rns_ros.resources import apply_loopback_profile

    context = rclpy.Context()
    player = None
    raise_on_sigterm()
    try:
        apply_loopback_profile()
        rclpy.init(args=[PROGRAM], context=context, signal_handler_options=SignalHandlerOptions.NO)
        player = Player(
            bag, rate=args.rate, clock_hz=args.clock, topics=args.topics, context=context
        )
        count = sum(bag.topics[name].message_count for name in player.topics)
        print(f"rns_bag: playing {bag.path}: {count} messages on {len(player.topics)} topics",
              flush=True)  # fmt: skip
        while True:
            time.sleep(args.delay)
            player.play_once()
            if not args.loop:
                break
    except KeyboardInterrupt:
        pass
    finally:
        if player is not None:
            player.close()
        rclpy.try_shutdown(context=context)
    print(f"rns_bag: published {player.published if player else 0} messages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
