"""The commands' work: load the inputs (description/), run the physics and studies, hand the typed results to
output/ (which formats and writes them). One module per workflow; the CLI calls these."""
