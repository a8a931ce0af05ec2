"""HTML reports: the demo's page, ``rodlab report DIR`` for any output folder, and every command's ``--report``."""
from .demo import is_run_folder, render_run
from .folder import CAPTIONS, classify, discover, render_sources, write_folder_report, write_sources_report
from .html import CSS, img_tag
from .sections import FORMAT_COMPARISON, FORMAT_MASS, FORMAT_SWEEP, SECTIONS, Section, Source

__all__ = ["write_folder_report", "write_sources_report", "render_sources", "render_run", "is_run_folder",
           "classify", "discover", "Source", "Section", "SECTIONS", "CAPTIONS", "CSS", "img_tag",
           "FORMAT_COMPARISON", "FORMAT_MASS", "FORMAT_SWEEP"]
