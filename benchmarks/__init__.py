"""Speed benchmarks: python -m benchmarks.NAME [--quick] [--json PATH]."""
