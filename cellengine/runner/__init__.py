"""Running a compiled plan on a driver: one place for the run's sequence, from a fresh start
(:func:`run_plan`) or from where a stopped run left off (:func:`resume_run`); the commands
only turn their arguments into these calls."""

from cellengine.runner.driver import DriverOptions
from cellengine.runner.run import resume_run, run_plan

__all__ = ["DriverOptions", "resume_run", "run_plan"]
