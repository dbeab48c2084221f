"""Applications layer: the command line, its commands, the study protocols (palpation, blind study),
campaigns and benchmarks. The top of the house: imports every layer below, nothing imports it."""
