"""The machine as data: strict schemas of machine files (models/) and case files (cases/)."""
