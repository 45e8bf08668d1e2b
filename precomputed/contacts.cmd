twoball sweep precomputed/contacts.zarr --eps 0.816 --mu 0.01:1/3:150:log --tau-ratio 1e-4:1:161:log --chunks 1,15,161 --dtype float32
