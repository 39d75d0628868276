"""Everything a user reads or keeps: the printout, CSV and spreadsheets, figures,
reports, the sweep's presentation, all written through `files.atomic_open`.

- `writers.WRITERS`: every file a command can write, one row each (the command
  line's options are made from it); `report.FORMATS`: the report formats.
- `tables`: the tables of a run, built once and rendered by every format.
- `words`: events, headings and units in words.
- `printout`, `sheets`, `plot`, `report/`, `sweeps`, `notebook`: the renderers.

Importing this package (or `files`, `writers`, `report`) loads no numpy; the
renderers do.
"""
