//! The numeric estimates of an identification, each once: what it is of ([`Quantity`],
//! whose key `block.name` is how the JSON and the report name it), value and 1-sigma
//! uncertainty. The JSON and the report both read this list, so a renamed estimate cannot
//! leave one of them behind.

use super::Identification;

/// What an estimate is of: one per number of the JSON's blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    ServovalveGain,
    ServovalveTimeConstant,
    ServovalveNaturalFrequency,
    ServovalveDampingRatio,
    /// The final mass (random and loop estimates together).
    Mass,
    MassRandom,
    MassPeriodic,
    Stiffness,
    OilColumnFrequency,
    OilColumnDampingRatio,
    BulkModulus,
    FrictionForce,
    FrictionYieldDisplacement,
    FrictionShape,
    TableTfError,
    TableTfErrorNonlinear,
    /// The identified model's table TF peak.
    PeakHz,
    MeasuredPeakHz,
    Leakage,
    DeviceForce,
    DeviceYieldDisplacement,
    DeviceShape,
    DeviceViscous,
    DeviceStiffness,
    DeviceMass,
    DeviceOffset,
    DeviceNrmse,
    DeviceFitPercent,
}

impl Quantity {
    /// Whether it is one of the device's ([`super::DeviceFit`]).
    pub fn is_device(self) -> bool {
        use Quantity::*;
        matches!(
            self,
            DeviceForce
                | DeviceYieldDisplacement
                | DeviceShape
                | DeviceViscous
                | DeviceStiffness
                | DeviceMass
                | DeviceOffset
                | DeviceNrmse
                | DeviceFitPercent
        )
    }

    /// The key `block.name` of the JSON (issue 5) and the report.
    pub fn key(self) -> &'static str {
        use Quantity::*;
        match self {
            ServovalveGain => "servovalve.gain",
            ServovalveTimeConstant => "servovalve.time_constant_s",
            ServovalveNaturalFrequency => "servovalve.natural_frequency_hz",
            ServovalveDampingRatio => "servovalve.damping_ratio",
            Mass => "table.mass_kg",
            MassRandom => "table.mass_random_kg",
            MassPeriodic => "table.mass_periodic_kg",
            Stiffness => "table.stiffness_n_m",
            OilColumnFrequency => "oil_column.frequency_hz",
            OilColumnDampingRatio => "oil_column.damping_ratio",
            BulkModulus => "oil_column.bulk_modulus_pa",
            FrictionForce => "friction.force_n",
            FrictionYieldDisplacement => "friction.yield_displacement_m",
            FrictionShape => "friction.shape",
            TableTfError => "validation.table_tf_error",
            TableTfErrorNonlinear => "validation.table_tf_error_nonlinear",
            PeakHz => "validation.peak_hz",
            MeasuredPeakHz => "validation.measured_peak_hz",
            Leakage => "actuator.leakage_m3_s_pa",
            DeviceForce => "device.force_n",
            DeviceYieldDisplacement => "device.yield_displacement_m",
            DeviceShape => "device.shape",
            DeviceViscous => "device.viscous_n_s_m",
            DeviceStiffness => "device.stiffness_n_m",
            DeviceMass => "device.mass_kg",
            DeviceOffset => "device.offset_n",
            DeviceNrmse => "device.nrmse",
            DeviceFitPercent => "device.fit_percent",
        }
    }
}

/// One estimate: `value` is `None` when it could not be made (see `missing`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub quantity: Quantity,
    pub value: Option<f64>,
    pub sigma: Option<f64>,
}

impl Estimate {
    /// The key `block.name` of the JSON and the report ([`Quantity::key`]).
    pub fn key(&self) -> &'static str {
        self.quantity.key()
    }
}

fn e(quantity: Quantity, value: Option<f64>, sigma: Option<f64>) -> Estimate {
    Estimate {
        quantity,
        value,
        sigma,
    }
}

impl Identification {
    /// Every numeric estimate, in the report's order.
    pub fn estimates(&self) -> Vec<Estimate> {
        let mut list = self.servovalve_estimates().to_vec();
        list.extend(self.table_estimates());
        list.extend(self.oil_column_estimates());
        list.extend(self.friction_estimates());
        list.extend(self.validation_estimates());
        let o = self.oil_column.as_ref();
        list.push(e(Quantity::Leakage, o.map(|o| o.leakage_m3_s_pa), None));
        list.extend(self.device_estimates());
        list
    }

    /// The servovalve's (4.1.1): the chosen order's gain, both orders' dynamics.
    fn servovalve_estimates(&self) -> [Estimate; 4] {
        use Quantity::*;
        let v = self.servovalve.as_ref();
        [
            e(ServovalveGain, v.map(|v| v.gain), None),
            e(
                ServovalveTimeConstant,
                v.map(|v| v.time_constant_s),
                v.map(|v| v.sigma_time_constant_s),
            ),
            e(
                ServovalveNaturalFrequency,
                v.map(|v| v.natural_frequency_hz),
                v.map(|v| v.sigma_natural_frequency_hz),
            ),
            e(
                ServovalveDampingRatio,
                v.map(|v| v.damping_ratio),
                v.map(|v| v.sigma_damping_ratio),
            ),
        ]
    }

    /// The table's: the final mass, each mass estimate, the triangles' stiffness.
    fn table_estimates(&self) -> [Estimate; 4] {
        use Quantity::*;
        let mr = self.mass_random.as_ref();
        let mp = self.mass_periodic.as_ref();
        let tri = self.triangles.as_ref();
        [
            e(Mass, self.mass_kg, None),
            e(
                MassRandom,
                mr.map(|m| m.mass_kg),
                mr.map(|m| m.sigma_mass_kg),
            ),
            e(
                MassPeriodic,
                mp.map(|m| m.mass_kg),
                mp.map(|m| m.sigma_mass_kg),
            ),
            e(
                Stiffness,
                tri.map(|t| t.stiffness_n_m),
                tri.map(|t| t.sigma_stiffness_n_m),
            ),
        ]
    }

    /// The oil column's (4.1.3).
    fn oil_column_estimates(&self) -> [Estimate; 3] {
        use Quantity::*;
        let o = self.oil_column.as_ref();
        [
            e(
                OilColumnFrequency,
                o.map(|o| o.frequency_hz),
                o.map(|o| o.sigma_frequency_hz),
            ),
            e(
                OilColumnDampingRatio,
                o.map(|o| o.damping_ratio),
                o.map(|o| o.sigma_damping_ratio),
            ),
            e(
                BulkModulus,
                o.map(|o| o.bulk_modulus_pa),
                o.map(|o| o.sigma_bulk_modulus_pa),
            ),
        ]
    }

    /// Bouc-Wen friction's (4.2.3).
    fn friction_estimates(&self) -> [Estimate; 3] {
        use Quantity::*;
        let fr = self.friction.as_ref();
        [
            e(
                FrictionForce,
                fr.map(|f| f.force_n),
                fr.map(|f| f.sigma_force_n),
            ),
            e(
                FrictionYieldDisplacement,
                fr.map(|f| f.yield_displacement_m),
                fr.map(|f| f.sigma_yield_displacement_m),
            ),
            e(
                FrictionShape,
                fr.map(|f| f.shape),
                fr.map(|f| f.sigma_shape),
            ),
        ]
    }

    /// The validation's (section 5): the table TF errors and peaks.
    fn validation_estimates(&self) -> [Estimate; 4] {
        use Quantity::*;
        let val = self.validation.as_ref();
        [
            e(TableTfError, val.map(|v| v.table_tf_error), None),
            e(
                TableTfErrorNonlinear,
                val.map(|v| v.table_tf_error_nonlinear),
                None,
            ),
            e(PeakHz, val.map(|v| v.peak_hz), None),
            e(
                MeasuredPeakHz,
                val.and_then(|v| v.measured_figures).map(|f| f.peak_hz),
                None,
            ),
        ]
    }

    /// The device's estimates (`device.*`; `null` when no test has displacement and
    /// force, see `missing`): the parameters of [`super::fit_device`] with sigma (listed
    /// in [`super::DeviceFit::sigma`]'s order), and the force fit on the test it was
    /// fitted on.
    fn device_estimates(&self) -> Vec<Estimate> {
        use Quantity::*;
        type Value = fn(&super::DeviceFit) -> f64;
        let parameters: [(Quantity, Value); 7] = [
            (DeviceForce, |d| d.force_n),
            (DeviceYieldDisplacement, |d| d.yield_displacement_m),
            (DeviceShape, |d| d.shape),
            (DeviceViscous, |d| d.viscous_n_s_m),
            (DeviceStiffness, |d| d.stiffness_n_m),
            (DeviceMass, |d| d.mass_kg),
            (DeviceOffset, |d| d.offset_n),
        ];
        let d = self.device.as_ref();
        let mut v: Vec<Estimate> = parameters
            .iter()
            .enumerate()
            .map(|(i, (q, value))| e(*q, d.map(value), d.and_then(|d| d.sigma.get(i).copied())))
            .collect();
        v.push(e(DeviceNrmse, d.map(|d| d.fit.nrmse), None));
        v.push(e(DeviceFitPercent, d.map(|d| d.fit.fit_percent), None));
        v
    }

    /// The estimate of `quantity`.
    pub fn estimate_of(&self, quantity: Quantity) -> Option<Estimate> {
        self.estimates()
            .into_iter()
            .find(|e| e.quantity == quantity)
    }

    /// The estimate whose key (`block.name`, [`Quantity::key`]) is `key`, if there is one.
    pub fn estimate(&self, key: &str) -> Option<Estimate> {
        self.estimates().into_iter().find(|e| e.key() == key)
    }
}
