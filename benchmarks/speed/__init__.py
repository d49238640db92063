"""What a run costs: step, compile, campaign throughput, floors (`python -m benchmarks.speed.NAME`)."""
