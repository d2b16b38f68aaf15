"""`lbr sweep`: parameter studies over the planners and controllers, fanned out on Dask.

A study file (TOML, :mod:`.spec`) names a run kind (:mod:`.kinds`: one small module per `lbr` command), fixed
options, the parameters to vary (grids, lists, seeded random samples) and the figures to collect. :mod:`.worker`
executes one run where Dask puts it (inputs and outputs are small picklable values), :mod:`.store` keeps every
completed run under the hash of its inputs (a study resumes where it stopped), :mod:`.engine` talks to Dask, and
:mod:`.table` writes the results (Parquet and CSV, one row per run).
"""
