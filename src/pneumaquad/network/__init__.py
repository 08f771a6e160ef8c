"""Networked co-simulation: wire protocol, sequence tracking and packet-timing analysis.

The thesis split its simulation over machines joined by UDP (Daepp 2011, ch. 5.1-5.3,
App. C.2.4). This package holds the pieces every process of such a split needs:

- :mod:`pneumaquad.network.protocol`: the versioned binary datagram format (24-byte
  header + float64 payload), its message types, per-type encoders and the ``STATE``
  fields (``docs/protocol.md`` is the normative description). It re-exports
  :mod:`~pneumaquad.network.wire` (framing and validation),
  :mod:`~pneumaquad.network.state` (``STATE`` layout) and
  :mod:`~pneumaquad.network.sequence` (serial-number arithmetic and per-peer tracking
  of duplicates, reorders and gaps);
- :mod:`pneumaquad.network.thesis`: the header-less 21-double layout of the thesis's
  SrLib ``SendNewData``/``ReceiveNewData`` (App. C.2.4), for thesis-compatible peers;
- :mod:`pneumaquad.network.packet_log`, :mod:`pneumaquad.network.timing` and
  :mod:`pneumaquad.network.timing_plots`: the per-packet log and the analysis that
  replaces the thesis's Wireshark work (ch. 5.3.1);
- :mod:`pneumaquad.network.dynamics_side` and :mod:`pneumaquad.network.actuator_side`:
  the two halves of the robot simulation (MuJoCo dynamics; cylinders, valves and
  controllers), which reproduce the in-process run bit for bit in lockstep;
- :mod:`pneumaquad.network.endpoint`, :mod:`pneumaquad.network.server` and
  :mod:`pneumaquad.network.client`: UDP endpoints (127.0.0.1 by default, optional peer
  filter), the dynamics server (lockstep or paced real time, timeouts, safe state,
  resynchronisation, packet log) and the actuator client;
- :mod:`pneumaquad.network.faults`: a fault-injection relay for tests and experiments.
"""
