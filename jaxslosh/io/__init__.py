"""The project's files: result files (SPEC section 3) and sweep files."""
