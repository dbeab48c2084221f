"""Control: command-path compensation (feed-forward) built on the effect models."""
