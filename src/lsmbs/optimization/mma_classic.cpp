#include "lsmbs/optimization/mma_classic.hpp"

#include <algorithm>
#include <cmath>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

namespace {

// Primal-dual state of the subproblem (names as in Svanberg's subsolv).
struct PdState {
  Vec x, y, lam, xsi, eta, mu, s;
  double z = 1, zet = 1;
};

// Residuals of the perturbed KKT conditions at relaxation epsi.
Vec kkt_residual(const MmaSubproblem& sp, const PdState& w, double epsi) {
  const Eigen::Index n = w.x.size(), m = w.y.size();
  const Vec ux1 = sp.upp - w.x, xl1 = w.x - sp.low;
  const Vec plam = sp.p0 + sp.P.transpose() * w.lam, qlam = sp.q0 + sp.Q.transpose() * w.lam;
  const Vec gvec = sp.P * ux1.cwiseInverse() + sp.Q * xl1.cwiseInverse();
  const Vec dpsidx =
      plam.cwiseQuotient(ux1.cwiseProduct(ux1)) - qlam.cwiseQuotient(xl1.cwiseProduct(xl1));
  Vec r(3 * n + 4 * m + 2);
  Eigen::Index k = 0;
  r.segment(k, n) = dpsidx - w.xsi + w.eta, k += n;
  r.segment(k, m) = sp.c + sp.d.cwiseProduct(w.y) - w.mu - w.lam, k += m;
  r[k++] = sp.a0 - w.zet - sp.a.dot(w.lam);
  r.segment(k, m) = gvec - sp.a * w.z - w.y + w.s - sp.b, k += m;
  r.segment(k, n) = (w.xsi.cwiseProduct(w.x - sp.alpha)).array() - epsi, k += n;
  r.segment(k, n) = (w.eta.cwiseProduct(sp.beta - w.x)).array() - epsi, k += n;
  r.segment(k, m) = (w.mu.cwiseProduct(w.y)).array() - epsi, k += m;
  r[k++] = w.zet * w.z - epsi;
  r.segment(k, m) = (w.lam.cwiseProduct(w.s)).array() - epsi;
  return r;
}

}  // namespace

MmaSubSolution solve_mma_subproblem(const MmaSubproblem& sp, double epsimin) {
  const Eigen::Index n = sp.low.size(), m = sp.b.size();
  PdState w;
  w.x = 0.5 * (sp.alpha + sp.beta);
  w.y = Vec::Ones(m);
  w.lam = Vec::Ones(m);
  w.xsi = (w.x - sp.alpha).cwiseInverse().cwiseMax(1.0);
  w.eta = (sp.beta - w.x).cwiseInverse().cwiseMax(1.0);
  w.mu = (0.5 * sp.c).cwiseMax(1.0);
  w.s = Vec::Ones(m);
  int itera = 0;
  for (double epsi = 1; epsi > epsimin; epsi *= 0.1) {
    Vec res = kkt_residual(sp, w, epsi);
    double resnorm = res.norm(), resmax = res.cwiseAbs().maxCoeff();
    for (int ittt = 0; resmax > 0.9 * epsi && ittt < 200; ++ittt) {
      ++itera;
      const Vec ux1 = sp.upp - w.x, xl1 = w.x - sp.low;
      const Vec ux2 = ux1.cwiseProduct(ux1), xl2 = xl1.cwiseProduct(xl1);
      const Vec ux3 = ux1.cwiseProduct(ux2), xl3 = xl1.cwiseProduct(xl2);
      const Vec plam = sp.p0 + sp.P.transpose() * w.lam, qlam = sp.q0 + sp.Q.transpose() * w.lam;
      const Vec gvec = sp.P * ux1.cwiseInverse() + sp.Q * xl1.cwiseInverse();
      const Mat GG =
          sp.P * ux2.cwiseInverse().asDiagonal() - sp.Q * xl2.cwiseInverse().asDiagonal();
      const Vec dpsidx = plam.cwiseQuotient(ux2) - qlam.cwiseQuotient(xl2);
      const Vec xa = w.x - sp.alpha, bx_ = sp.beta - w.x;
      const Vec delx = dpsidx - epsi * xa.cwiseInverse() + epsi * bx_.cwiseInverse();
      const Vec dely = sp.c + sp.d.cwiseProduct(w.y) - w.lam - epsi * w.y.cwiseInverse();
      const double delz = sp.a0 - sp.a.dot(w.lam) - epsi / w.z;
      const Vec dellam = gvec - sp.a * w.z - w.y - sp.b + epsi * w.lam.cwiseInverse();
      const Vec diagx = 2 * (plam.cwiseQuotient(ux3) + qlam.cwiseQuotient(xl3)) +
                        w.xsi.cwiseQuotient(xa) + w.eta.cwiseQuotient(bx_);
      const Vec diagy = sp.d + w.mu.cwiseQuotient(w.y);
      const Vec diaglamyi = w.s.cwiseQuotient(w.lam) + diagy.cwiseInverse();
      Vec dx, dlam;
      double dz;
      if (m < n) {
        Mat A(m + 1, m + 1);
        A.topLeftCorner(m, m) = GG * diagx.cwiseInverse().asDiagonal() * GG.transpose();
        A.topLeftCorner(m, m).diagonal() += diaglamyi;
        A.topRightCorner(m, 1) = sp.a;
        A.bottomLeftCorner(1, m) = sp.a.transpose();
        A(m, m) = -w.zet / w.z;
        Vec bb(m + 1);
        bb.head(m) = dellam + dely.cwiseQuotient(diagy) - GG * delx.cwiseQuotient(diagx);
        bb[m] = delz;
        const Vec sol = A.partialPivLu().solve(bb);
        dlam = sol.head(m);
        dz = sol[m];
        dx = -delx.cwiseQuotient(diagx) - (GG.transpose() * dlam).cwiseQuotient(diagx);
      } else {
        const Vec dli = diaglamyi.cwiseInverse();
        const Vec dellamyi = dellam + dely.cwiseQuotient(diagy);
        Mat A(n + 1, n + 1);
        A.topLeftCorner(n, n) = GG.transpose() * dli.asDiagonal() * GG;
        A.topLeftCorner(n, n).diagonal() += diagx;
        const Vec axz = -GG.transpose() * sp.a.cwiseProduct(dli);
        A.topRightCorner(n, 1) = axz;
        A.bottomLeftCorner(1, n) = axz.transpose();
        A(n, n) = w.zet / w.z + sp.a.dot(sp.a.cwiseProduct(dli));
        Vec bb(n + 1);
        bb.head(n) = -(delx + GG.transpose() * dellamyi.cwiseProduct(dli));
        bb[n] = -(delz - sp.a.dot(dellamyi.cwiseProduct(dli)));
        const Vec sol = A.partialPivLu().solve(bb);
        dx = sol.head(n);
        dz = sol[n];
        dlam =
            (GG * dx).cwiseProduct(dli) - dz * sp.a.cwiseProduct(dli) + dellamyi.cwiseProduct(dli);
      }
      const Vec dy = -dely.cwiseQuotient(diagy) + dlam.cwiseQuotient(diagy);
      const Vec dxsi = -w.xsi + epsi * xa.cwiseInverse() - w.xsi.cwiseProduct(dx).cwiseQuotient(xa);
      const Vec deta =
          -w.eta + epsi * bx_.cwiseInverse() + w.eta.cwiseProduct(dx).cwiseQuotient(bx_);
      const Vec dmu = -w.mu + epsi * w.y.cwiseInverse() - w.mu.cwiseProduct(dy).cwiseQuotient(w.y);
      const double dzet = -w.zet + epsi / w.z - w.zet * dz / w.z;
      const Vec ds =
          -w.s + epsi * w.lam.cwiseInverse() - w.s.cwiseProduct(dlam).cwiseQuotient(w.lam);
      // largest step keeping every positive quantity positive (fraction 1/1.01 of the boundary)
      double stm = 1;
      auto limit = [&stm](const Vec& v, const Vec& dv) {
        for (Eigen::Index i = 0; i < v.size(); ++i) stm = std::max(stm, -1.01 * dv[i] / v[i]);
      };
      limit(w.y, dy), limit(w.lam, dlam), limit(w.xsi, dxsi), limit(w.eta, deta), limit(w.mu, dmu),
          limit(w.s, ds);
      stm = std::max({stm, -1.01 * dz / w.z, -1.01 * dzet / w.zet});
      for (Eigen::Index j = 0; j < n; ++j)
        stm = std::max({stm, -1.01 * dx[j] / xa[j], 1.01 * dx[j] / bx_[j]});
      double steg = 1 / stm;
      const PdState old = w;
      double resnew = 2 * resnorm;
      for (int itto = 0; resnew > resnorm && itto < 50; ++itto) {
        w.x = old.x + steg * dx, w.y = old.y + steg * dy, w.z = old.z + steg * dz,
        w.lam = old.lam + steg * dlam;
        w.xsi = old.xsi + steg * dxsi, w.eta = old.eta + steg * deta, w.mu = old.mu + steg * dmu;
        w.zet = old.zet + steg * dzet, w.s = old.s + steg * ds;
        res = kkt_residual(sp, w, epsi);
        resnew = res.norm();
        steg /= 2;
      }
      resnorm = resnew;
      resmax = res.cwiseAbs().maxCoeff();
    }
  }
  if (!w.x.allFinite())
    throw NumericalFailure("MMA subproblem: the interior-point iteration produced NaN or Inf");
  return {w.x, w.y, w.lam, w.z, itera};
}

std::string MmaOptions::validate() const {
  if (!(asyinit > 0 && asyinit <= 1))
    return "asyinit: expected a fraction of the variable range in (0, 1]";
  if (!(asyincr >= 1)) return "asyincr: expected a factor >= 1";
  if (!(asydecr > 0 && asydecr <= 1)) return "asydecr: expected a factor in (0, 1]";
  if (!(move > 0 && move <= 1)) return "move: expected a fraction of the variable range in (0, 1]";
  if (!(albefa > 0 && albefa < 1)) return "albefa: expected a value in (0, 1)";
  if (!(c > 0) || !std::isfinite(c)) return "c: expected a positive finite penalty";
  if (!(raa0 > 0) || !std::isfinite(raa0)) return "raa0: expected a positive finite regularization";
  return {};
}

MmaClassic::MmaClassic(Vec xmin, Vec xmax, int m, MmaOptions o)
    : xmin_(std::move(xmin)), xmax_(std::move(xmax)), m_(m), o_(o), lam_(Vec::Zero(m)) {
  if (auto msg = o_.validate(); !msg.empty()) throw Error("MMA option " + msg);
  if (xmin_.size() != xmax_.size() || !((xmax_ - xmin_).array() > 0).all())
    throw Error("MMA: every variable needs xmin < xmax");
}

Vec MmaClassic::step(const Vec& x, const Vec& df0, const Vec& f, const Mat& df) {
  const Eigen::Index n = x.size();
  if (f.size() != m_ || df.rows() != m_ || df.cols() != n || df0.size() != n)
    throw Error("MMA: inconsistent sizes of the function values and gradients");
  ++iter_;
  const Vec range = xmax_ - xmin_;
  // asymptotes (Svanberg 1987, section 4; mmasub)
  if (iter_ <= 2) {
    low_ = x - o_.asyinit * range;
    upp_ = x + o_.asyinit * range;
  } else {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double zzz = (x[j] - xold1_[j]) * (xold1_[j] - xold2_[j]);
      const double factor = zzz > 0 ? o_.asyincr : zzz < 0 ? o_.asydecr : 1.0;
      low_[j] = x[j] - factor * (xold1_[j] - low_[j]);
      upp_[j] = x[j] + factor * (upp_[j] - xold1_[j]);
      low_[j] = std::clamp(low_[j], x[j] - 10 * range[j], x[j] - 0.01 * range[j]);
      upp_[j] = std::clamp(upp_[j], x[j] + 0.01 * range[j], x[j] + 10 * range[j]);
    }
  }
  MmaSubproblem sp;
  sp.low = low_, sp.upp = upp_;
  sp.alpha.resize(n), sp.beta.resize(n), sp.p0.resize(n), sp.q0.resize(n);
  sp.P.resize(m_, n), sp.Q.resize(m_, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    sp.alpha[j] =
        std::max({low_[j] + o_.albefa * (x[j] - low_[j]), x[j] - o_.move * range[j], xmin_[j]});
    sp.beta[j] =
        std::min({upp_[j] - o_.albefa * (upp_[j] - x[j]), x[j] + o_.move * range[j], xmax_[j]});
    const double ux2 = (upp_[j] - x[j]) * (upp_[j] - x[j]),
                 xl2 = (x[j] - low_[j]) * (x[j] - low_[j]);
    const double reg = o_.raa0 / std::max(range[j], 1e-5);
    auto pq = [&](double g, double& p, double& q) {
      const double pp = std::max(g, 0.0), qq = std::max(-g, 0.0), r = 0.001 * (pp + qq) + reg;
      p = (pp + r) * ux2;
      q = (qq + r) * xl2;
    };
    pq(df0[j], sp.p0[j], sp.q0[j]);
    for (int i = 0; i < m_; ++i) pq(df(i, j), sp.P(i, j), sp.Q(i, j));
  }
  // b_i = Σ_j P_ij/(u_j − x_j) + Q_ij/(x_j − l_j) − f_i: the approximation is exact at x
  sp.b = sp.P * (upp_ - x).cwiseInverse() + sp.Q * (x - low_).cwiseInverse() - f;
  sp.a = Vec::Zero(m_);
  sp.c = Vec::Constant(m_, o_.c);
  sp.d = Vec::Ones(m_);
  sp.a0 = 1;
  const MmaSubSolution sol = solve_mma_subproblem(sp);
  xold2_ = xold1_.size() ? xold1_ : x;
  xold1_ = x;
  lam_ = sol.lam;
  return sol.x;
}

}  // namespace lsmbs
