"""suvtwin pipeline: roads, scenarios, the ground-truth simulator, scoring, reports, the CLI.

Data flows one way: roads → vehicle model → simulation → identification /
estimation → scoring → report.
"""
