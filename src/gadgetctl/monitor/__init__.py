"""Sample statistics, recording and replay used by ``gadgetctl monitor``.

The first six modules do not depend on the input manager (plain records in, plain records
out); the last two run it:

* :mod:`~gadgetctl.monitor.records`: the record types and their NDJSON encoding;
* :mod:`~gadgetctl.monitor.recording`: :class:`Recorder` and :func:`read_recording`;
* :mod:`~gadgetctl.monitor.stats`: running per-device statistics and recording summaries;
* :mod:`~gadgetctl.monitor.sparkline`: values to a fixed-width unicode sparkline;
* :mod:`~gadgetctl.monitor.replay`: replay timing (speed, loop, device renaming);
* :mod:`~gadgetctl.monitor.units`: display units and rotation conversions;
* :mod:`~gadgetctl.monitor.session`: :class:`MonitorSession`, which runs the input manager
  frame by frame, gathers every sample, keeps the statistics, writes records and hands the
  views their snapshots, with its parts in modules of their own:
  :mod:`~gadgetctl.monitor.gather` (a frame's samples by device),
  :mod:`~gadgetctl.monitor.tracks` (what is kept per device between frames),
  :mod:`~gadgetctl.monitor.encoding` (samples and proxy values as records, their numbers
  written by :mod:`~gadgetctl.monitor.numbertext`) and
  :mod:`~gadgetctl.monitor.views` (the snapshots views draw);
* :mod:`~gadgetctl.monitor.replaydevice`: the replay driver (``replay_device``) and the
  thread that feeds a recording into it.

The record format is described in ``docs/recording-format.md``.
"""
