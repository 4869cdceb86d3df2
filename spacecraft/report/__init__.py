"""What a run leaves behind: the output folder, report pages, plots, results.json, time series
and FMUs.

:mod:`.output` claims an output folder before the work starts (complete or absent, locked
against simultaneous writers); :mod:`.write` writes a run's report (:func:`write_report`) from
blocks that :mod:`.pages` renders as Markdown and HTML; :mod:`.plots` draws the figures;
:mod:`.results` writes strict JSON and the time series; :mod:`.exports` builds the FMUs and SSP
files a scene asks for.
"""

from .output import OutputError, OutputFolder, output_folder
from .write import write_report

__all__ = ["OutputError", "OutputFolder", "output_folder", "write_report"]
