"""Tables (Markdown, CSV, LaTeX, JSON) and figures shared by the suites and sweeps."""
