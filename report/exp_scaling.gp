set terminal png size 800,500 noenhanced
set output 'report/exp_scaling.png'
csv = 'report/exp_scaling.csv'
set datafile separator ','
set key outside
set grid
set logscale xy
set xlabel 'triangles'
set ylabel 'primary Mrays/s'
plot for [k in 'brute grid nested_grid bvh'] csv using ($4):(strcol(2) eq k && strcol(1) eq 'soup' ? $10 : 1/0) with linespoints title k
