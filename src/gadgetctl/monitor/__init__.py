"""Sample statistics, recording and replay used by ``gadgetctl monitor``.

Nothing here depends on the input manager: the integration hands plain records over.

* :mod:`~gadgetctl.monitor.records`: the record types and their NDJSON encoding;
* :mod:`~gadgetctl.monitor.recording`: :class:`Recorder` and :func:`read_recording`;
* :mod:`~gadgetctl.monitor.stats`: running per-device statistics and recording summaries;
* :mod:`~gadgetctl.monitor.sparkline`: values to a fixed-width unicode sparkline;
* :mod:`~gadgetctl.monitor.replay`: replay timing (speed, loop, device renaming);
* :mod:`~gadgetctl.monitor.units`: display units and rotation conversions.

The record format is described in ``docs/recording-format.md``.
"""
