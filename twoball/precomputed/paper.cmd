twoball sweep twoball/precomputed/paper.zarr --eps 0.5:1:50 --mu 0.01:1/3:50 --tau-ratio 0.01:1:50 --dtype float32
