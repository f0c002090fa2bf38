#include "lsmbs/fem/hex_element.hpp"

#include <cmath>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using B6 = Eigen::Matrix<double, 6, 24>;
using Mat24 = Eigen::Matrix<double, 24, 24>;
using Vec24 = Eigen::Matrix<double, 24, 1>;

Mat6 svk_voigt(double E, double nu) {
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>().setConstant(lambda);
  for (int i = 0; i < 3; ++i) C(i, i) += 2 * mu;
  for (int i = 3; i < 6; ++i) C(i, i) = mu;
  return C;
}

Mat6 svk_voigt_nu_derivative(double E, double nu) {
  // λ = E ν / ((1 + ν)(1 − 2ν)): dλ/dν = E (1 + 2ν²) / ((1 + ν)(1 − 2ν))²; μ = E / (2(1 + ν))
  const double d = (1 + nu) * (1 - 2 * nu);
  const double dl = E * (1 + 2 * nu * nu) / (d * d), dmu = -E / (2 * (1 + nu) * (1 + nu));
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>().setConstant(dl);
  for (int i = 0; i < 3; ++i) C(i, i) += 2 * dmu;
  for (int i = 3; i < 6; ++i) C(i, i) = dmu;
  return C;
}

namespace {

constexpr double kCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                  {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// N_I and ∂N_I/∂ξ at a natural point
void shape(const Vec3& s, Eigen::Matrix<double, 8, 1>& N, Eigen::Matrix<double, 8, 3>& dN) {
  for (int I = 0; I < 8; ++I) {
    const double a = 1 + s[0] * kCorner[I][0], b = 1 + s[1] * kCorner[I][1],
                 c = 1 + s[2] * kCorner[I][2];
    N[I] = a * b * c / 8;
    dN(I, 0) = kCorner[I][0] * b * c / 8;
    dN(I, 1) = a * kCorner[I][1] * c / 8;
    dN(I, 2) = a * b * kCorner[I][2] / 8;
  }
}

// J(i, j) = ∂X_i/∂ξ_j
Mat3 jacobian(const std::array<Vec3, 8>& X, const Eigen::Matrix<double, 8, 3>& dN) {
  Mat3 J = Mat3::Zero();
  for (int I = 0; I < 8; ++I) J += X[static_cast<size_t>(I)] * dN.row(I);
  return J;
}

// A symmetric tensor in Voigt strain components (engineering shears)
Vec6 voigt_strain(const Mat3& T) {
  Vec6 v;
  v << T(0, 0), T(1, 1), T(2, 2), 2 * T(0, 1), 2 * T(1, 2), 2 * T(0, 2);
  return v;
}

Mat3 stress_tensor(const Vec6& S) {
  Mat3 T;
  T << S[0], S[3], S[5], S[3], S[1], S[4], S[5], S[4], S[2];
  return T;
}

// Green–Lagrange strain of F (Voigt) and B = ∂E/∂x (6 × 3n) from F and the gradients G (n × 3)
template <int N>
void strain_and_b(const Mat3& F, const Eigen::Matrix<double, N, 3>& G, Vec6& E,
                  Eigen::Matrix<double, 6, 3 * N>& B) {
  const Mat3 C = F.transpose() * F;
  E << (C(0, 0) - 1) / 2, (C(1, 1) - 1) / 2, (C(2, 2) - 1) / 2, C(0, 1), C(1, 2), C(0, 2);
  for (int I = 0; I < N; ++I)
    for (int i = 0; i < 3; ++i) {
      const int c = 3 * I + i;
      B(0, c) = F(i, 0) * G(I, 0);
      B(1, c) = F(i, 1) * G(I, 1);
      B(2, c) = F(i, 2) * G(I, 2);
      B(3, c) = F(i, 0) * G(I, 1) + F(i, 1) * G(I, 0);
      B(4, c) = F(i, 1) * G(I, 2) + F(i, 2) * G(I, 1);
      B(5, c) = F(i, 0) * G(I, 2) + F(i, 2) * G(I, 0);
    }
}

// K_σ: the geometric stiffness (G_Iᵀ S G_J) δ_ij of one point, added with weight w
template <int N>
void add_geometric(const Eigen::Matrix<double, N, 3>& G, const Vec6& S, double w,
                   Eigen::Matrix<double, 3 * N, 3 * N>& K) {
  const Eigen::Matrix<double, N, N> g = G * stress_tensor(S) * G.transpose();
  for (int I = 0; I < N; ++I)
    for (int J = 0; J < N; ++J)
      for (int i = 0; i < 3; ++i) K(3 * I + i, 3 * J + i) += w * g(I, J);
}

// The natural enhanced modes (a, b, polynomial variable) of the nine parameters
constexpr int kMode[9][3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {0, 1, 0}, {0, 1, 1},
                             {1, 2, 1}, {1, 2, 2}, {0, 2, 0}, {0, 2, 2}};

}  // namespace

HexElement::HexElement(const std::array<Vec3, 8>& X, Formulation f)
    : enhanced_(f == Formulation::kEnhanced) {
  Eigen::Matrix<double, 8, 1> N;
  Eigen::Matrix<double, 8, 3> dN;
  shape(Vec3::Zero(), N, dN);
  const Mat3 J0 = jacobian(X, dN);
  const double j0 = J0.determinant();
  if (!(j0 > 0))
    throw Error("inverted or degenerate hexahedral element (det J <= 0 at its centre)");
  const Mat3 A0 = J0.inverse();  // E_cart = A0ᵀ E_nat A0
  G_centre_ = dN * A0;
  const double g = 1 / std::sqrt(3.0);
  for (int p = 0; p < 8; ++p) {
    const Vec3 s(g * kCorner[p][0], g * kCorner[p][1], g * kCorner[p][2]);
    shape(s, N, dN);
    const Mat3 J = jacobian(X, dN);
    const double j = J.determinant();
    if (!(j > 0))
      throw Error("inverted or badly distorted hexahedral element (det J <= 0 at a Gauss point)");
    Point& P = gp_[static_cast<size_t>(p)];
    P.G = dN * J.inverse();
    P.wj = j;
    P.M.setZero();
    if (enhanced_)
      for (int k = 0; k < 9; ++k) {
        Mat3 T = Mat3::Zero();
        const int a = kMode[k][0], b = kMode[k][1];
        if (a == b)
          T(a, a) = 1;
        else
          T(a, b) = T(b, a) = 0.5;
        P.M.col(k) = (j0 / j) * s[kMode[k][2]] * voigt_strain(A0.transpose() * T * A0);
      }
  }
  // mass and shape integrals: 3 × 3 × 3 Gauss (N_I N_J j is of degree 4 in each variable)
  unit_mass_ = Eigen::MatrixXd::Zero(8, 8);
  shape_int_ = Eigen::VectorXd::Zero(8);
  const double r = std::sqrt(0.6), pts[3] = {-r, 0, r}, wts[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c) {
        shape(Vec3(pts[a], pts[b], pts[c]), N, dN);
        const double w = wts[a] * wts[b] * wts[c] * jacobian(X, dN).determinant();
        unit_mass_ += w * N * N.transpose();
        shape_int_ += w * N;
        volume_ += w;
      }
}

struct HexElement::Eval {
  std::array<Vec6, 8> Ec;
  std::array<B6, 8> B;
  Eigen::LDLT<Mat9> H;
  Vec9 alpha = Vec9::Zero();
  Eigen::Matrix<double, 9, 24> Gamma = Eigen::Matrix<double, 9, 24>::Zero();
  Vec6 strain(size_t p, const Point& P) const { return Ec[p] + P.M * alpha; }
};

void HexElement::evaluate(const double* x, const Mat6& C, Eval& ev) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 8>> xm(x);
  Vec9 L = Vec9::Zero();
  Mat9 H = Mat9::Zero();
  for (size_t p = 0; p < 8; ++p) {
    const Point& P = gp_[p];
    const Mat3 F = xm * P.G;
    strain_and_b<8>(F, P.G, ev.Ec[p], ev.B[p]);
    if (enhanced_) {
      const Eigen::Matrix<double, 9, 6> MC = P.M.transpose() * C;
      L += P.wj * MC * ev.Ec[p];
      H += P.wj * MC * P.M;
      ev.Gamma += P.wj * MC * ev.B[p];
    }
  }
  if (enhanced_) {
    ev.H.compute(H);
    ev.alpha = -ev.H.solve(L);
  }
}

void HexElement::internal_force(const double* x, double E, double nu, double* f, double* K) const {
  const Mat6 C = svk_voigt(E, nu);
  Eval ev;
  evaluate(x, C, ev);
  Eigen::Map<Vec24> fv(f);
  fv.setZero();
  Mat24 Km = Mat24::Zero();
  for (size_t p = 0; p < 8; ++p) {
    const Point& P = gp_[p];
    const Vec6 S = C * ev.strain(p, P);
    fv += P.wj * ev.B[p].transpose() * S;
    if (K) {
      Km += P.wj * ev.B[p].transpose() * C * ev.B[p];
      add_geometric<8>(P.G, S, P.wj, Km);
    }
  }
  if (K) {
    if (enhanced_) Km -= ev.Gamma.transpose() * ev.H.solve(ev.Gamma);
    Eigen::Map<Mat24> Kout(K);
    Kout = Km;
  }
}

void HexElement::internal_force_nu_derivative(const double* x, double E, double nu,
                                              double* df) const {
  const Mat6 C = svk_voigt(E, nu), dC = svk_voigt_nu_derivative(E, nu);
  Eval ev;
  evaluate(x, C, ev);
  // α = −H⁻¹L: α' = −H⁻¹ (H' α + L'), H' and L' with C' in place of C
  Vec9 dalpha = Vec9::Zero();
  if (enhanced_) {
    Vec9 r = Vec9::Zero();
    for (size_t p = 0; p < 8; ++p) {
      const Point& P = gp_[p];
      r += P.wj * P.M.transpose() * dC * ev.strain(p, P);
    }
    dalpha = -ev.H.solve(r);
  }
  Eigen::Map<Vec24> d(df);
  d.setZero();
  for (size_t p = 0; p < 8; ++p) {
    const Point& P = gp_[p];
    d += P.wj * ev.B[p].transpose() * (dC * ev.strain(p, P) + C * P.M * dalpha);
  }
}

double HexElement::strain_energy(const double* x, double E, double nu) const {
  const Mat6 C = svk_voigt(E, nu);
  Eval ev;
  evaluate(x, C, ev);
  double W = 0;
  for (size_t p = 0; p < 8; ++p) {
    const Vec6 e = ev.strain(p, gp_[p]);
    W += gp_[p].wj * 0.5 * e.dot(C * e);
  }
  return W;
}

Eigen::Matrix<double, 9, 1> HexElement::enhanced_parameters(const double* x, double E,
                                                            double nu) const {
  Eval ev;
  evaluate(x, svk_voigt(E, nu), ev);
  return ev.alpha;
}

Eigen::Matrix<double, 6, 1> HexElement::centre_stress(const double* x, double E, double nu) const {
  // M(0) = 0: the enhanced modes vanish at the centre
  const Eigen::Map<const Eigen::Matrix<double, 3, 8>> xm(x);
  Vec6 e;
  B6 B;
  strain_and_b<8>(xm * G_centre_, G_centre_, e, B);
  return svk_voigt(E, nu) * e;
}

Mat3 HexElement::centre_F(const double* x) const {
  return Eigen::Map<const Eigen::Matrix<double, 3, 8>>(x) * G_centre_;
}

double HexElement::min_det_F(const double* x) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 8>> xm(x);
  double m = (xm * G_centre_).determinant();
  for (const Point& P : gp_) m = std::min(m, (xm * P.G).determinant());
  return m;
}

// ---------------------------------------------------------------- tetrahedron

TetElement::TetElement(const std::array<Vec3, 4>& X) {
  Mat3 J;
  for (int k = 0; k < 3; ++k) J.col(k) = X[static_cast<size_t>(k + 1)] - X[0];
  const double det = J.determinant();
  if (!(det > 0)) throw Error("inverted or degenerate tetrahedral element (det J <= 0)");
  volume_ = det / 6;
  // N_0 = 1 − ξ − η − ζ, N_k = ξ_k: ∇_ξ N rows (−1,−1,−1), e1, e2, e3; ∇_X N = ∇_ξ N J⁻¹
  Eigen::Matrix<double, 4, 3> dN;
  dN << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  G_ = dN * J.inverse();
  unit_mass_ = Eigen::MatrixXd::Constant(4, 4, volume_ / 20);
  unit_mass_.diagonal() *= 2;
  shape_int_ = Eigen::VectorXd::Constant(4, volume_ / 4);
}

void TetElement::internal_force(const double* x, double E, double nu, double* f, double* K) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 4>> xm(x);
  const Mat6 C = svk_voigt(E, nu);
  Vec6 e;
  Eigen::Matrix<double, 6, 12> B;
  strain_and_b<4>(xm * G_, G_, e, B);
  const Vec6 S = C * e;
  Eigen::Map<Eigen::Matrix<double, 12, 1>> fout(f);
  fout = volume_ * B.transpose() * S;
  if (K) {
    Eigen::Matrix<double, 12, 12> Km = volume_ * B.transpose() * C * B;
    add_geometric<4>(G_, S, volume_, Km);
    Eigen::Map<Eigen::Matrix<double, 12, 12>> Kout(K);
    Kout = Km;
  }
}

void TetElement::internal_force_nu_derivative(const double* x, double E, double nu,
                                              double* df) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 4>> xm(x);
  Vec6 e;
  Eigen::Matrix<double, 6, 12> B;
  strain_and_b<4>(xm * G_, G_, e, B);
  Eigen::Map<Eigen::Matrix<double, 12, 1>> dout(df);
  dout = volume_ * B.transpose() * svk_voigt_nu_derivative(E, nu) * e;
}

double TetElement::strain_energy(const double* x, double E, double nu) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 4>> xm(x);
  Vec6 e;
  Eigen::Matrix<double, 6, 12> B;
  strain_and_b<4>(xm * G_, G_, e, B);
  return volume_ * 0.5 * e.dot(svk_voigt(E, nu) * e);
}

Eigen::Matrix<double, 6, 1> TetElement::centre_stress(const double* x, double E, double nu) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 4>> xm(x);
  Vec6 e;
  Eigen::Matrix<double, 6, 12> B;
  strain_and_b<4>(xm * G_, G_, e, B);
  return svk_voigt(E, nu) * e;
}

Mat3 TetElement::centre_F(const double* x) const {
  return Eigen::Map<const Eigen::Matrix<double, 3, 4>>(x) * G_;
}

double TetElement::min_det_F(const double* x) const {
  const Eigen::Map<const Eigen::Matrix<double, 3, 4>> xm(x);
  return (xm * G_).determinant();
}

}  // namespace lsmbs
