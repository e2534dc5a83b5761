//! The numeric estimates of an identification, each once: its key (`block.name`, as the
//! JSON and the report name it), value and 1-sigma uncertainty. The JSON and the report
//! both read this list, so a renamed estimate cannot leave one of them behind.

use super::Identification;

/// One estimate: `value` is `None` when it could not be made (see `missing`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub key: &'static str,
    pub value: Option<f64>,
    pub sigma: Option<f64>,
}

fn e(key: &'static str, value: Option<f64>, sigma: Option<f64>) -> Estimate {
    Estimate { key, value, sigma }
}

impl Identification {
    /// Every numeric estimate, in the report's order.
    pub fn estimates(&self) -> Vec<Estimate> {
        let v = self.servovalve.as_ref();
        let o = self.oil_column.as_ref();
        let fr = self.friction.as_ref();
        let val = self.validation.as_ref();
        let mr = self.mass_random.as_ref();
        let mp = self.mass_periodic.as_ref();
        let tri = self.triangles.as_ref();
        let mut list = vec![
            e("servovalve.gain", v.map(|v| v.gain), None),
            e(
                "servovalve.time_constant_s",
                v.map(|v| v.time_constant_s),
                v.map(|v| v.sigma_time_constant_s),
            ),
            e(
                "servovalve.natural_frequency_hz",
                v.map(|v| v.natural_frequency_hz),
                v.map(|v| v.sigma_natural_frequency_hz),
            ),
            e(
                "servovalve.damping_ratio",
                v.map(|v| v.damping_ratio),
                v.map(|v| v.sigma_damping_ratio),
            ),
            e("table.mass_kg", self.mass_kg, None),
            e(
                "table.mass_random_kg",
                mr.map(|m| m.mass_kg),
                mr.map(|m| m.sigma_mass_kg),
            ),
            e(
                "table.mass_periodic_kg",
                mp.map(|m| m.mass_kg),
                mp.map(|m| m.sigma_mass_kg),
            ),
            e(
                "table.stiffness_n_m",
                tri.map(|t| t.stiffness_n_m),
                tri.map(|t| t.sigma_stiffness_n_m),
            ),
            e(
                "oil_column.frequency_hz",
                o.map(|o| o.frequency_hz),
                o.map(|o| o.sigma_frequency_hz),
            ),
            e(
                "oil_column.damping_ratio",
                o.map(|o| o.damping_ratio),
                o.map(|o| o.sigma_damping_ratio),
            ),
            e(
                "oil_column.bulk_modulus_pa",
                o.map(|o| o.bulk_modulus_pa),
                o.map(|o| o.sigma_bulk_modulus_pa),
            ),
            e(
                "friction.force_n",
                fr.map(|f| f.force_n),
                fr.map(|f| f.sigma_force_n),
            ),
            e(
                "friction.yield_displacement_m",
                fr.map(|f| f.yield_displacement_m),
                fr.map(|f| f.sigma_yield_displacement_m),
            ),
            e(
                "friction.shape",
                fr.map(|f| f.shape),
                fr.map(|f| f.sigma_shape),
            ),
            e(
                "validation.table_tf_error",
                val.map(|v| v.table_tf_error),
                None,
            ),
            e(
                "validation.table_tf_error_nonlinear",
                val.map(|v| v.table_tf_error_nonlinear),
                None,
            ),
            e("validation.peak_hz", val.map(|v| v.peak_hz), None),
            e(
                "validation.measured_peak_hz",
                val.and_then(|v| v.measured_figures).map(|f| f.peak_hz),
                None,
            ),
            e(
                "actuator.leakage_m3_s_pa",
                o.map(|o| o.leakage_m3_s_pa),
                None,
            ),
        ];
        list.extend(self.device_estimates());
        list
    }

    /// The device's estimates (`device.*`; `null` when no test has displacement and
    /// force, see `missing`): the parameters of [`super::fit_device`] with sigma, and the
    /// force fit on the test it was fitted on.
    fn device_estimates(&self) -> Vec<Estimate> {
        let d = self.device.as_ref();
        let keys = [
            "device.force_n",
            "device.yield_displacement_m",
            "device.shape",
            "device.viscous_n_s_m",
            "device.stiffness_n_m",
            "device.mass_kg",
            "device.offset_n",
        ];
        let values = d.map(|d| {
            [
                d.force_n,
                d.yield_displacement_m,
                d.shape,
                d.viscous_n_s_m,
                d.stiffness_n_m,
                d.mass_kg,
                d.offset_n,
            ]
        });
        let mut v: Vec<Estimate> = keys
            .iter()
            .enumerate()
            .map(|(i, k)| {
                e(
                    *k,
                    values.map(|x| x[i]),
                    d.and_then(|d| d.sigma.get(i).copied()),
                )
            })
            .collect();
        v.push(e("device.nrmse", d.map(|d| d.fit.nrmse), None));
        v.push(e("device.fit_percent", d.map(|d| d.fit.fit_percent), None));
        v
    }

    /// The estimate named `key`, if there is such an estimate.
    pub fn estimate(&self, key: &str) -> Option<Estimate> {
        self.estimates().into_iter().find(|e| e.key == key)
    }
}
