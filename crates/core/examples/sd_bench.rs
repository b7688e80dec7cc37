// Temporary: timing of signed distances (not committed).
use machscan_core::mesh::{signed_distances, SignedMesh};
use std::time::Instant;
fn main() {
    let n = 158usize;
    // lumpy ellipsoid like bench_deviation
    let mut v = vec![];
    let stacks = n; let slices = 2*n;
    v.push([0.0,0.0,40.0*0.7]);
    for i in 1..stacks { let th = std::f64::consts::PI*i as f64/stacks as f64;
        for j in 0..slices { let ph = 2.0*std::f64::consts::PI*j as f64/slices as f64;
            let p = [40.0*th.sin()*ph.cos()*1.5, 40.0*th.sin()*ph.sin(), 40.0*th.cos()*0.7];
            let s = 1.0 + 0.15*(3.0*p[0]/40.0).sin()*(2.0*p[1]/40.0).cos();
            v.push([p[0]*s,p[1]*s,p[2]*s]); } }
    v.push([0.0,0.0,-40.0*0.7]);
    let last = (v.len()-1) as u32; let ring = |i: usize, j: usize| (1 + (i-1)*slices + j%slices) as u32;
    let mut f = vec![];
    for j in 0..slices { f.push([0, ring(1,j), ring(1,j+1)]); f.push([last, ring(stacks-1,j+1), ring(stacks-1,j)]); }
    for i in 1..stacks-1 { for j in 0..slices { f.push([ring(i,j), ring(i+1,j), ring(i+1,j+1)]); f.push([ring(i,j), ring(i+1,j+1), ring(i,j+1)]); } }
    // queries: vertices jittered, sorted along y lines then x
    let mut seed = 1u64; let mut rnd = || { seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); (seed>>11) as f64/(1u64<<53) as f64 };
    let mut q: Vec<[f64;3]> = (0..1_000_000).map(|_| { let t = f[(rnd()*f.len() as f64) as usize % f.len()]; let (a,b) = (rnd(), rnd()); let (a,b) = if a+b>1.0 {(1.0-a,1.0-b)} else {(a,b)};
        let p: Vec<f64> = (0..3).map(|k| v[t[0] as usize][k] + a*(v[t[1] as usize][k]-v[t[0] as usize][k]) + b*(v[t[2] as usize][k]-v[t[0] as usize][k])).collect();
        let r = (p[0]*p[0]+p[1]*p[1]+p[2]*p[2]).sqrt(); let o = rnd()-0.5; [p[0]+o*p[0]/r, p[1]+o*p[1]/r, p[2]+o*p[2]/r] }).collect();
    q.sort_by(|a,b| ((a[1]/0.2).round(), a[0]).partial_cmp(&((b[1]/0.2).round(), b[0])).unwrap());
    println!("{} tris", f.len());
    for _ in 0..3 {
        let t = Instant::now(); let m = SignedMesh::new(&v,&f).unwrap(); let s = t.elapsed();
        let t = Instant::now(); let r = m.signed_distances(&q); let e = t.elapsed();
        let t = Instant::now(); let r2 = signed_distances(&v,&f,&q).unwrap(); let e2 = t.elapsed();
        println!("setup {:?} queries {:?} total {:?} {}", s, e, e2, r[7].distance + r2[7].distance);
    }
    let t = Instant::now(); let o = machscan_core::geom::morton_order(&q); println!("morton {:?} {}", t.elapsed(), o[0]);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| { let m = SignedMesh::new(&v,&f).unwrap(); let t = Instant::now(); let r = m.signed_distances(&q); println!("1 thread queries {:?} {}", t.elapsed(), r[3].distance); });
}
