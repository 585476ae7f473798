"""Recording topics into MCAP files and playing them back (docs/recording.md).

`ln_record` (record_cli.py) is an ordinary client: it subscribes to the chosen topics in
queued mode and writes their samples into rotating MCAP files (split_writer.py) with the
mapping of links_and_nodes.mcap_format; `ln_play` (play_cli.py, player.py) publishes the
samples of such files again with their original relative timing.
"""
