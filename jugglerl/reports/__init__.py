"""Reports: the robustness benchmark (``robustness``) and the tables that compare runs
(``run_tables``), as Markdown and plots for ``docs/``."""
