"""The run report: report.json and a self-contained report.html.

:func:`write_report` writes both; :func:`report_data` (report.json's content) and
:func:`replay_data` (what the page draws) are pure and testable on their own.
"""

from cellengine.report.data import report_data
from cellengine.report.replay import replay_data
from cellengine.report.write import write_report

__all__ = ["replay_data", "report_data", "write_report"]
