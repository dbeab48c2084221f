"""Benchmarks, one module per `teleop bench KIND`; each defines ``register(subparsers)``.
Benchmarks live apart from the tests: tests never assert wall-clock times."""
