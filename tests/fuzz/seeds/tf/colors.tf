colorspace Lab
color 0 0.23 0.30 0.75
color 0.5 0.86 0.86 0.86
color 1 0.71 0.02 0.15
opacity 0 0
opacity 1 1
