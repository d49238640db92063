"""The project's files: result files (docs/reference/files.md) and sweep files."""
