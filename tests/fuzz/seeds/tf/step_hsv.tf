colorspace Step
color 0 0 0 0
color 1 1 1 1
colorspace HSV
