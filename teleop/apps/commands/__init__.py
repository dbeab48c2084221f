"""One module per `teleop` subcommand; each defines ``register(subparsers)``. Keep imports light at
module level (heavy imports inside the handler) so `teleop --help` stays fast."""
