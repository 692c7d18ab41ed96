"""suvtwin pipeline, the top layer: scenarios, ground-truth simulators, campaigns, scoring, reports, CLI.

Data flows one way: roads → vehicle model → simulation → identification /
estimation → scoring → report.
"""

if __name__ != "suvtwin.pipeline":  # imported by its bare folder name
    raise ImportError(f"import suvtwin.pipeline, not {__name__} (suvtwin's layers are suvtwin.<layer>)")
