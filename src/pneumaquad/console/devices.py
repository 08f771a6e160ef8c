"""External input devices over UDP: stylus positions in, haptic feedback forces out.

A device (a haptic stylus driver, a joystick bridge, a script) sends ``DEVICE_INPUT``
datagrams in the protocol-v1 framing (:mod:`pneumaquad.network.protocol`,
``docs/protocol.md``) to the console's device port and receives ``DEVICE_FEEDBACK``
datagrams on the socket it sent from. Payloads (float64):

* ``DEVICE_INPUT`` (5 values): leg index (``robot.legs`` order: 0 front_left,
  1 front_right, 2 rear_left, 3 rear_right), stylus tip x, y, z in the device frame [m]
  (the device frame has the thorax frame's axes: the stylus displacement of the console's
  teleoperation), buttons bitmask (:data:`BUTTON_ENGAGE`, :data:`BUTTON_PLACE_FOOT`).
  Header sender time: the device's monotonic clock [s].
* ``DEVICE_FEEDBACK`` (6 values): leg index, device force x, y, z [N] (device frame),
  contact normal force of the foot [N], clamped flag (1: the IK target was out of reach).
  Header sender time: the console's simulation time [s].

While the engage button is held, the device position drives the leg's stylus through
:meth:`FootTeleoperation.set_stylus` (offset and scale as for the mouse gizmo); released,
the target stays. An input older than the stale timeout (0.5 s) is ignored: a lost device
leaves its stylus where it was. Documentation: ``docs/console.md``.
"""

from __future__ import annotations

import contextlib
import select
import socket
import threading
import time
from collections import Counter
from dataclasses import dataclass

import numpy as np

from pneumaquad.network.protocol import (
    SEQUENCE_MODULUS,
    Message,
    MessageType,
    ProtocolError,
    SequenceTracker,
    decode,
    encode,
)
from pneumaquad.robot.feedback import (
    DEFAULT_DEVICE_SCALE,
    DEFAULT_MAX_DEVICE_FORCE,
    FootFeedback,
    device_force,
)
from pneumaquad.robot.simulation import RobotSimulation

from .teleop import FootTeleoperation

__all__ = [
    "BUTTON_ENGAGE", "BUTTON_PLACE_FOOT", "DEFAULT_STALE_TIMEOUT", "DeviceFeedback",
    "DeviceInput", "DeviceLink", "DeviceServer", "ReceivedInput", "decode_device_feedback",
    "decode_device_input", "device_forces", "encode_device_feedback", "encode_device_input",
    "feedback_status",
]

#: Button bit 0: while pressed, the device position drives the foot target.
BUTTON_ENGAGE = 1 << 0
#: Button bit 1: "place foot": in shared-control walking, the front foot's next foothold is
#: where the device points when the button is pressed (and stays there until pressed again).
BUTTON_PLACE_FOOT = 1 << 1
#: Largest leg index a device message may carry (four legs).
MAX_LEG_INDEX = 3
#: Buttons are an integer bitmask below this bound.
BUTTONS_LIMIT = 1 << 16
#: Age [s] after which a device input is stale (device lost).
DEFAULT_STALE_TIMEOUT = 0.5


@dataclass(frozen=True)
class DeviceInput:
    """One decoded ``DEVICE_INPUT``: stylus tip position [m] (device frame) and buttons."""

    leg_index: int
    position: np.ndarray
    buttons: int
    sequence: int = 0
    sender_time: float = 0.0

    @property
    def engaged(self) -> bool:
        """Whether the engage button (bit 0) is pressed."""
        return bool(self.buttons & BUTTON_ENGAGE)


@dataclass(frozen=True)
class DeviceFeedback:
    """One decoded ``DEVICE_FEEDBACK``: device force [N], foot normal force [N], clamped."""

    leg_index: int
    force: np.ndarray
    normal_force: float
    clamped: bool
    sequence: int = 0
    simulation_time: float = 0.0


def _integer(value: float, name: str, upper: int) -> int:
    """``value`` as an integer in 0 .. upper - 1, else ``ProtocolError("bad_count")``."""
    if value != int(value) or not 0 <= value < upper:
        raise ProtocolError("bad_count", f"{name} {value} is not an integer in 0..{upper - 1}")
    return int(value)


def _message(datagram: Message | bytes, message_type: MessageType) -> Message:
    message = datagram if isinstance(datagram, Message) else decode(datagram)
    if message.type != message_type:
        raise ValueError(f"expected a {message_type.name}, got {message.type.name}")
    return message


def encode_device_input(sequence: int, monotonic_time: float, leg_index: int,
                        position: np.ndarray, buttons: int) -> bytes:
    """Encode a ``DEVICE_INPUT``: leg index, stylus x, y, z [m], buttons bitmask."""
    _integer(leg_index, "leg index", MAX_LEG_INDEX + 1)
    _integer(buttons, "buttons", BUTTONS_LIMIT)
    values = [leg_index, *np.asarray(position, dtype=float).reshape(3), buttons]
    return encode(MessageType.DEVICE_INPUT, sequence, monotonic_time, values)


def decode_device_input(datagram: Message | bytes) -> DeviceInput:
    """Fields of a ``DEVICE_INPUT``; ``ProtocolError`` (``decode``'s reasons, or
    ``"bad_count"`` for a leg index / buttons value that is not an integer in range)."""
    message = _message(datagram, MessageType.DEVICE_INPUT)
    values = message.values
    return DeviceInput(_integer(values[0], "leg index", MAX_LEG_INDEX + 1),
                       np.array(values[1:4]), _integer(values[4], "buttons", BUTTONS_LIMIT),
                       message.sequence, message.sender_time)


def encode_device_feedback(sequence: int, simulation_time: float, leg_index: int,
                           force: np.ndarray, normal_force: float, clamped: bool) -> bytes:
    """Encode a ``DEVICE_FEEDBACK``: leg, device force x, y, z [N], normal force [N], clamped."""
    _integer(leg_index, "leg index", MAX_LEG_INDEX + 1)
    values = [leg_index, *np.asarray(force, dtype=float).reshape(3), normal_force,
              1.0 if clamped else 0.0]
    return encode(MessageType.DEVICE_FEEDBACK, sequence, simulation_time, values)


def decode_device_feedback(datagram: Message | bytes) -> DeviceFeedback:
    """Fields of a ``DEVICE_FEEDBACK`` (``ProtocolError`` like :func:`decode_device_input`)."""
    message = _message(datagram, MessageType.DEVICE_FEEDBACK)
    values = message.values
    return DeviceFeedback(_integer(values[0], "leg index", MAX_LEG_INDEX + 1),
                          np.array(values[1:4]), float(values[4]),
                          bool(_integer(values[5], "clamped flag", 2)),
                          message.sequence, message.sender_time)


@dataclass
class ReceivedInput:
    """The latest input of one leg: the message, its arrival (monotonic [s]) and sender."""

    input: DeviceInput
    arrival: float
    sender: tuple[str, int]
    taken: bool = False


class DeviceServer:
    """UDP endpoint for input devices; a background thread keeps the latest input per leg.

    Parameters
    ----------
    host : str
        Interface to bind (loopback by default: no authentication).
    port : int
        UDP port; 0 picks a free one (see :attr:`port`).
    stale_timeout : float
        Age [s] after which an input is stale and ignored.
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0,
                 stale_timeout: float = DEFAULT_STALE_TIMEOUT) -> None:
        self.stale_timeout = stale_timeout
        self.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.socket.bind((host, port))
        self.malformed: Counter[str] = Counter()  # dropped datagrams by protocol reason
        self.dropped_old = 0  # duplicates / reordered (not newer than the sender's newest)
        self.ignored = 0  # valid datagrams of other types
        self.sequence = 0
        self._trackers: dict[tuple[str, int], SequenceTracker] = {}
        self._latest: dict[int, ReceivedInput] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._receive_loop, name="console-devices",
                                        daemon=True)
        self._thread.start()

    @property
    def host(self) -> str:
        """The bound interface."""
        return str(self.socket.getsockname()[0])

    @property
    def port(self) -> int:
        """The bound UDP port."""
        return int(self.socket.getsockname()[1])

    @property
    def malformed_count(self) -> int:
        """Malformed datagrams dropped so far [count]."""
        return sum(self.malformed.values())

    def _receive_loop(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self.socket], [], [], 0.05)
                if not ready:
                    continue
                datagram, sender = self.socket.recvfrom(2048)
            except (OSError, ValueError):  # closed under us
                return
            self.receive(datagram, sender, time.monotonic())

    def receive(self, datagram: bytes, sender: tuple[str, int], arrival: float) -> None:
        """Validate one datagram and keep it as its leg's latest input (else count it)."""
        try:
            message = decode(datagram)
            if message.type != MessageType.DEVICE_INPUT:
                self.ignored += 1
                return
            device_input = decode_device_input(message)
        except ProtocolError as error:
            self.malformed[error.reason] += 1
            return
        tracker = self._trackers.setdefault(sender, SequenceTracker())
        if not tracker.classify(device_input.sequence).accepted:
            self.dropped_old += 1
            return
        with self._lock:
            self._latest[device_input.leg_index] = ReceivedInput(device_input, arrival, sender)

    def latest(self, leg_index: int, now: float | None = None) -> ReceivedInput | None:
        """The latest input of ``leg_index``, None when there is none or it is stale."""
        now = time.monotonic() if now is None else now
        with self._lock:
            received = self._latest.get(leg_index)
        if received is None or now - received.arrival > self.stale_timeout:
            return None
        return received

    def take_fresh(self, now: float | None = None) -> dict[int, DeviceInput]:
        """Inputs that arrived since the last call and are not stale, by leg index."""
        now = time.monotonic() if now is None else now
        fresh = {}
        with self._lock:
            for leg_index, received in self._latest.items():
                if not received.taken and now - received.arrival <= self.stale_timeout:
                    received.taken = True
                    fresh[leg_index] = received.input
        return fresh

    def send_feedback(self, leg_index: int, force: np.ndarray, normal_force: float,
                      clamped: bool, simulation_time: float, now: float | None = None) -> bool:
        """Send ``DEVICE_FEEDBACK`` to the last (non-stale) sender of ``leg_index``."""
        received = self.latest(leg_index, now)
        if received is None:
            return False
        datagram = encode_device_feedback(self.sequence, simulation_time, leg_index, force,
                                          normal_force, clamped)
        self.sequence = (self.sequence + 1) % SEQUENCE_MODULUS
        with contextlib.suppress(OSError):
            self.socket.sendto(datagram, received.sender)
            return True
        return False

    def close(self) -> None:
        """Stop the receiving thread and close the socket."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.socket.close()


def device_forces(simulation: RobotSimulation, feedback: FootFeedback,
                  scale: float = DEFAULT_DEVICE_SCALE,
                  max_force: float = DEFAULT_MAX_DEVICE_FORCE) -> np.ndarray:
    """(legs, 3) device forces [N]: total foot feedback in the device (thorax) frame.

    The world-frame total force of each foot is rotated into the thorax frame (the frame
    of the stylus displacements, so position and force share their axes), then scaled
    and saturated by :func:`pneumaquad.robot.feedback.device_force`.
    """
    thorax_rotation = simulation.data.xmat[simulation.robot.thorax_id].reshape(3, 3)
    in_thorax_frame = feedback.total @ thorax_rotation  # row k: R^T F_k
    return np.array([device_force(force, scale, max_force) for force in in_thorax_frame])


def feedback_status(simulation: RobotSimulation, feedback: FootFeedback,
                    legs: tuple[str, ...] | list[str], link: DeviceLink | None = None) -> str:
    """Markdown readout: feedback force norm at the foot and at the device, per leg."""
    scale = DEFAULT_DEVICE_SCALE if link is None else link.scale
    max_force = DEFAULT_MAX_DEVICE_FORCE if link is None else link.max_force
    forces = device_forces(simulation, feedback, scale, max_force)
    lines = []
    for leg in legs:
        index = feedback.legs.index(leg)
        engaged = ", **engaged**" if link is not None and leg in link.engaged else ""
        lines.append(f"{leg} feedback: {np.linalg.norm(feedback.total[index]):.1f} N at the "
                     f"foot, {np.linalg.norm(forces[index]):.2f} N at the device{engaged}")
    if link is not None:
        server = link.server
        lines.append(f"Devices: udp {server.host}:{server.port}, "
                     f"{server.malformed_count} malformed datagrams")
    return "  \n".join(lines)


class DeviceLink:
    """Connects a :class:`DeviceServer` to the console's teleoperation and foot feedback.

    Parameters
    ----------
    server : DeviceServer
    scale : float
        Device newtons per foot newton [N/N].
    max_force : float
        Saturation of the device force norm [N].
    """

    def __init__(self, server: DeviceServer, scale: float = DEFAULT_DEVICE_SCALE,
                 max_force: float = DEFAULT_MAX_DEVICE_FORCE) -> None:
        self.server = server
        self.scale = scale
        self.max_force = max_force
        self.engaged: set[str] = set()
        #: Front legs whose footholds the place-foot button chooses (thorax-frame target
        #: [m] of the latest press), for shared-control walking.
        self.placed: dict[str, np.ndarray] = {}
        #: Presses not yet handed to the walking (:meth:`take_placements`).
        self._new_placements: dict[str, np.ndarray] = {}
        self._pressed: set[str] = set()

    def apply_inputs(self, teleop: FootTeleoperation, legs: tuple[str, ...]) -> list[str]:
        """Move the stylus of every leg with a fresh, engaged input; return those legs.

        A press of the place-foot button (its rising edge, engaged or not) moves the
        stylus to the device position and records the foot target as that leg's placed
        foothold (:attr:`placed`, :meth:`take_placements`).
        """
        moved = []
        for leg_index, device_input in self.server.take_fresh().items():
            leg = legs[leg_index] if leg_index < len(legs) else None
            if leg not in teleop.legs:
                continue
            placing = bool(device_input.buttons & BUTTON_PLACE_FOOT)
            if device_input.engaged or (placing and leg not in self._pressed):
                teleop.set_stylus(leg, device_input.position)
                moved.append(leg)
            if device_input.engaged:
                self.engaged.add(leg)
            else:
                self.engaged.discard(leg)
            if placing and leg not in self._pressed:
                target = teleop.legs[leg].target.copy()
                self.placed[leg] = target
                self._new_placements[leg] = target
            if placing:
                self._pressed.add(leg)
            else:
                self._pressed.discard(leg)
        return moved

    def take_placements(self) -> dict[str, np.ndarray]:
        """The place-foot presses since the last call: leg → foot target [m] (thorax
        frame) at the press."""
        placements, self._new_placements = self._new_placements, {}
        return placements

    def clear_placements(self) -> None:
        """Forget every placed foothold (the styluses choose the footholds again)."""
        self.placed.clear()
        self._new_placements.clear()

    def device_forces(self, simulation: RobotSimulation,
                      feedback: FootFeedback) -> np.ndarray:
        """(legs, 3) device forces [N], device (thorax) frame, scaled and saturated."""
        return device_forces(simulation, feedback, self.scale, self.max_force)

    def send_feedback(self, simulation: RobotSimulation, teleop: FootTeleoperation,
                      feedback: FootFeedback) -> int:
        """Send ``DEVICE_FEEDBACK`` to each leg's live device; return how many were sent."""
        forces = self.device_forces(simulation, feedback)
        normal_forces = simulation.foot_normal_forces()
        sent = 0
        for leg_index, leg in enumerate(feedback.legs):
            state = teleop.legs.get(leg)
            clamped = state is not None and state.clamped
            sent += self.server.send_feedback(leg_index, forces[leg_index],
                                              float(normal_forces[leg_index]), clamped,
                                              simulation.time)
        return sent

    def close(self) -> None:
        """Close the server."""
        self.server.close()
