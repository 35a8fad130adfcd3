"""Everything that writes: atomic files, plots, tables and reports."""
