// placeholder until the metrics land
