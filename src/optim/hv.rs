//! Exact hypervolume (minimisation, dominated region bounded by a reference point) and IGD.
//!
//! Two objectives: a sort and sweep. More: slicing along the last objective (HSO), each
//! slab measured by the hypervolume of one dimension less — exact, O(n^(d−1) log n), fine
//! for the population sizes used here.

/// Points strictly better than `r` in every objective, non-dominated among themselves.
pub fn nondominated_below(points: &[Vec<f64>], r: &[f64]) -> Vec<Vec<f64>> {
    let inside: Vec<&[f64]> = points.iter().filter(|p| p.iter().zip(r).all(|(a, b)| a < b)).map(|p| p.as_slice()).collect();
    // first front by the fast non-dominated sort, then drop repeated points
    let rank = super::sort::pareto_ranks(&inside);
    let mut out: Vec<Vec<f64>> = inside.iter().zip(&rank).filter(|(_, r)| **r == 0).map(|(p, _)| p.to_vec()).collect();
    out.sort_by(|a, b| a.iter().zip(b).map(|(x, y)| x.total_cmp(y)).find(|o| o.is_ne()).unwrap_or(std::cmp::Ordering::Equal));
    out.dedup();
    out
}

/// Exact hypervolume of `points` with respect to the reference point `r`.
pub fn hypervolume(points: &[Vec<f64>], r: &[f64]) -> f64 {
    let pts = nondominated_below(points, r);
    hv_rec(pts, r)
}

fn hv_rec(mut pts: Vec<Vec<f64>>, r: &[f64]) -> f64 {
    let d = r.len();
    if pts.is_empty() {
        return 0.0;
    }
    if d == 1 {
        return r[0] - pts.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    }
    if d == 2 {
        pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
        let mut hv = 0.0;
        let mut best_y = r[1];
        for p in &pts {
            if p[1] < best_y {
                hv += (r[0] - p[0]) * (best_y - p[1]);
                best_y = p[1];
            }
        }
        return hv;
    }
    // slice along the last objective
    pts.sort_by(|a, b| a[d - 1].total_cmp(&b[d - 1]));
    let mut hv = 0.0;
    for i in 0..pts.len() {
        let z = pts[i][d - 1];
        let next = if i + 1 < pts.len() { pts[i + 1][d - 1] } else { r[d - 1] };
        if next > z {
            let proj: Vec<Vec<f64>> = pts[..=i].iter().map(|p| p[..d - 1].to_vec()).collect();
            let proj = nondominated_below(&proj, &r[..d - 1]);
            hv += (next - z) * hv_rec(proj, &r[..d - 1]);
        }
    }
    hv
}

/// Inverted generational distance: mean over the reference front of the distance to the
/// nearest point of `points`.
pub fn igd(points: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    if points.is_empty() {
        return f64::INFINITY;
    }
    let s: f64 = reference
        .iter()
        .map(|z| points.iter().map(|p| p.iter().zip(z).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()).fold(f64::INFINITY, f64::min))
        .sum();
    s / reference.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_computed_2d() {
        // staircase (1,3), (2,2), (3,1) with r = (4, 4): 3 + 2 + 1 = 6
        let p = vec![vec![1.0, 3.0], vec![2.0, 2.0], vec![3.0, 1.0]];
        assert!((hypervolume(&p, &[4.0, 4.0]) - 6.0).abs() < 1e-15);
        // a dominated point and a point outside the box change nothing
        let mut q = p.clone();
        q.push(vec![3.0, 3.0]);
        q.push(vec![5.0, 0.0]);
        assert!((hypervolume(&q, &[4.0, 4.0]) - 6.0).abs() < 1e-15);
        assert_eq!(hypervolume(&[vec![4.0, 1.0]], &[4.0, 4.0]), 0.0);
    }

    #[test]
    fn hand_computed_3d_and_4d() {
        // single point: box volume
        assert!((hypervolume(&[vec![0.0, 0.0, 0.0]], &[1.0, 2.0, 3.0]) - 6.0).abs() < 1e-15);
        // two boxes [0,2]×[0,1]×[0,1] ∪ [0,1]×[0,2]×[0,1] in r = (2,2,1)… from points
        // (0,1,0) and (1,0,0) with r = (2,2,1): 2·1·1 + 1·2·1 − 1·1·1 = 3
        let p = vec![vec![0.0, 1.0, 0.0], vec![1.0, 0.0, 0.0]];
        assert!((hypervolume(&p, &[2.0, 2.0, 1.0]) - 3.0).abs() < 1e-15);
        // 3 points of the unit simplex corners in r = (1,1,1): three unit cubes minus overlaps
        let p = vec![vec![0.0, 0.5, 0.5], vec![0.5, 0.0, 0.5], vec![0.5, 0.5, 0.0]];
        // inclusion–exclusion: 3·(1·0.5·0.5) − 3·(0.5·0.5·0.5) + 0.5³ = 0.75 − 0.375 + 0.125
        assert!((hypervolume(&p, &[1.0, 1.0, 1.0]) - 0.5).abs() < 1e-15);
        let p4 = vec![vec![0.0, 0.0, 0.0, 0.5], vec![0.5, 0.5, 0.5, 0.0]];
        // 1·1·1·0.5 + 0.5·0.5·0.5·1 − 0.5·0.5·0.5·0.5
        assert!((hypervolume(&p4, &[1.0, 1.0, 1.0, 1.0]) - (0.5 + 0.125 - 0.0625)).abs() < 1e-15);
    }

    #[test]
    fn monte_carlo_agreement_4d() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let pts: Vec<Vec<f64>> = (0..25).map(|_| (0..4).map(|_| rng.random_range(0.0..1.0)).collect()).collect();
        let r = [1.0; 4];
        let exact = hypervolume(&pts, &r);
        let n = 400_000;
        let mut hits = 0;
        for _ in 0..n {
            let z: Vec<f64> = (0..4).map(|_| rng.random_range(0.0..1.0)).collect();
            if pts.iter().any(|p| p.iter().zip(&z).all(|(a, b)| a <= b)) {
                hits += 1;
            }
        }
        let mc = hits as f64 / n as f64;
        let sigma = (mc * (1.0 - mc) / n as f64).sqrt();
        assert!((exact - mc).abs() < 5.0 * sigma, "exact {exact} mc {mc} ± {sigma}");
    }

    #[test]
    fn igd_of_the_reference_itself_is_zero() {
        let r = vec![vec![0.0, 1.0], vec![1.0, 0.0]];
        assert_eq!(igd(&r, &r), 0.0);
        assert!((igd(&[vec![0.0, 0.0]], &r) - 1.0).abs() < 1e-15);
    }
}
