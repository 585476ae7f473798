"""`ln_bag`: inspect and rework MCAP recordings of ln_record (docs/recording.md, "Working
with recordings: ln_bag"): info, cut, filter, merge, convert, split, export.  Every
subcommand streams its inputs (memory does not grow with file size)."""
