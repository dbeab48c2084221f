"""One module per `teleop` subcommand; each defines ``register(subparsers)``. Imports are at the top of each
module (teleop.apps.cli imports every command to build the parser); only matplotlib and dask load where a
figure is drawn or a campaign runs on Dask."""
