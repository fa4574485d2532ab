"""fillet_correction: the fillet-foundation stiffness in double contact (thesis future work, physics 5).

Physical mismatch. The fillet-foundation term of Sainsot et al. (eq. 2.41-2.46) assumes one
loaded tooth: it is the deflection of the gear body under that tooth alone. In double
contact the neighbouring loaded tooth deforms the same body, so each tooth's foundation is
softer than the formula says and the PEM overestimates the double-contact stiffness (thesis
6.2, item 5; Ma et al. 2016, Xie et al. 2018 quantify it against FEM). The thesis keeps the
uncorrected term (docs/physics.md decision 7).

Realisation. While two or more tooth pairs carry load, each loaded pair's compliance gains
a fraction lambda of its own fillet compliances (pinion and gear, eq. 2.42):

    1/k_n' = 1/k_n + lambda (1/k_f1,n + 1/k_f2,n)     (double contact only),

and the TVMS becomes sum_n k_n'. lambda stands in for the FEM-calibrated coupling the thesis
asks for; single contact is unchanged. The fillet term is 50-70 % of a pair's compliance in
both thesis presets, so lambda = 0.25 lowers the double-contact stiffness by about 12-15 %.

Symmetry. Built per tooth: it shifts with a faulted tooth, the symmetry holds.

Bounds. lambda from 0 (the thesis's model) to 1 (the neighbour's load doubles the foundation
deflection: the upper limit of equal load sharing on a shared foundation). Default 0.25.
"""

from gearlab.api import Effect, fillet_compliance, hookimpl, parameters, setting

LAM_DOC = "extra fillet compliance in double contact, as a fraction of the pair's own"


class FilletCorrection(Effect):
    name = "fillet_correction"
    doc = "softer fillet foundation while two tooth pairs are loaded (double-contact overestimate of eq. 2.41-2.46)"
    params = parameters(lam=setting(float, 0.25, low=0.0, high=1.0, doc=LAM_DOC))

    def apply_excitation(self, exc, params):
        lam = params["lam"]
        if lam == 0.0 or not exc.stiffness.options.fillet:
            return exc
        pair = exc.pair
        phi, in_mesh, k = exc.tooth_pairs()
        loaded = in_mesh & (k > 0)
        double = loaded.sum(axis=0) >= 2
        p = phi[loaded & double]
        fillet = fillet_compliance(
            pair.pinion, pair.alpha1_pinion(p), pair.pinion.E, pair.face_width
        ) + fillet_compliance(pair.gear, pair.alpha1_gear(p), pair.gear.E, pair.face_width)  # each gear's own E
        corrected = k.copy()
        corrected[loaded & double] = 1.0 / (1.0 / k[loaded & double] + lam * fillet)
        # as a change to the current table, so it composes with any other table effect
        return exc.with_tvms(exc.tvms.k + corrected.sum(axis=0) - k.sum(axis=0))


@hookimpl
def gearlab_effects():
    return [FilletCorrection()]
