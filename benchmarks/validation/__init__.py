"""The physics against references: closed forms, experiments, other codes (`python -m benchmarks.validation.NAME`)."""
