"""What a run writes and reports: history, fields, probes, summary, figures, checkpoints."""
