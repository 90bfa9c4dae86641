"""The shared node main(): Ctrl-C / SIGTERM end the spin with exit code 0 without raising inside
node code, while the Context still works, so destroy_node() can publish a final zero."""

from __future__ import annotations

import os
import signal
import threading

import pytest
import rclpy
from rclpy.node import Node
from std_msgs.msg import String

from rns_ros.nodes.runner import run_node


class _Busy(Node):
    """Publishes every millisecond; the signal comes from another thread after 0.3 s (``kill``)
    or is delivered by calling the installed handler inside a timer callback (``in_callback``:
    where a raising handler can land in rclpy's C++ message conversion, seen in CI as a
    RuntimeError and exit code 1)."""

    def __init__(self, signum: int, delivery: str) -> None:
        super().__init__("rns_runner_test")
        self.signum = signum
        self.delivery = delivery
        self.publisher = self.create_publisher(String, "rns_runner_test", 10)
        self.ticks = 0
        self.raised: list[BaseException] = []
        self.final: list[bool] = []
        self.create_timer(0.001, self._tick)
        if delivery == "kill":
            threading.Timer(0.3, os.kill, (os.getpid(), signum)).start()

    def _tick(self) -> None:
        self.ticks += 1
        self.publisher.publish(String(data="x" * 256))
        if self.delivery == "in_callback" and self.ticks == 100:
            try:
                signal.getsignal(self.signum)(self.signum, None)
            except BaseException as exc:  # whatever it is, it must not happen
                self.raised.append(exc)
        if self.ticks == 5000:  # still spinning 5 s on: stop the test run the hard way
            os.kill(os.getpid(), signal.SIGINT)

    def destroy_node(self) -> None:
        # what the controller does on shutdown: one last message, which needs a live Context
        self.final.append(rclpy.ok())
        self.publisher.publish(String(data="stop"))
        super().destroy_node()


@pytest.mark.parametrize("delivery", ["kill", "in_callback"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_spin_with_exit_code_0_and_a_live_context_for_the_last_words(
    signum, delivery
):
    nodes: list[_Busy] = []

    def factory() -> _Busy:
        nodes.append(_Busy(signum, delivery))
        return nodes[-1]

    before = signal.getsignal(signum)
    code = run_node(factory, executable="rns_runner_test", summary="", specs=(), args=["test"])
    assert code == 0
    assert nodes[0].raised == []  # the handler only asks the spin loop to stop
    assert nodes[0].final == [True]  # destroy_node ran before the Context was shut down
    assert signal.getsignal(signum) is before  # our handler is gone again
    assert not rclpy.ok()
