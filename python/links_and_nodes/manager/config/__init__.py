"""Reading `.lnc` configuration files into the typed model of `model.py`."""
