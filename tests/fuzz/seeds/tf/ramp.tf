# soft ramp
colormap viridis
opacity 0 0
opacity 0.3 0 0.5 0.2
opacity 1 0.8
range -1.5 2.5
density 2
table 512
