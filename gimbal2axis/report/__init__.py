"""Comparison reports: one scene run under several gyro grades and stabilization schemes, written
as one page a person reads (gimbal2axis report)."""
from .comparison import Comparison, load_comparison, run_comparison
from .page import write_page

__all__ = ["Comparison", "load_comparison", "run_comparison", "write_page"]
