//! Speller recordings played as one unlabelled session (`oddball_decode::unsupervised`'s replay), then scored: the
//! labels are read only after the decoder has finished, to count what it got right.

use oddball_io::Speller;
use oddball_signal::{Epochs, Events, SignalError};
use serde::Serialize;

use crate::evaluate::{labels, pooled_accuracy, score_speller, EpochedRecording, EvaluateError};
use oddball_decode::metrics::{character_of_flashes, roc_auc};
use oddball_decode::pipeline::{EpochSource, Preprocess};
use oddball_decode::unsupervised::{
    feature_times, replay_starts, Constraint, Covariance, MatchedTemplate, P300Template,
    PooledPattern, PooledStart, Start, UnsupervisedError, UnsupervisedParams,
};
use oddball_decode::DecodeError;

/// Why an unsupervised replay could not run or be scored.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error("{recording} is not a speller recording: an unsupervised replay needs its characters (rows and columns)")]
    NotSpeller { recording: String },
    #[error("{recording} flashes other codes than {first} ({a:?} vs {b:?}); one session needs one speller layout")]
    DifferentLayout {
        recording: String,
        first: String,
        a: Vec<Vec<u32>>,
        b: Vec<Vec<u32>>,
    },
    #[error("no recordings to replay")]
    Empty,
    #[error("{recording}: character {character} has no single target row and column, so it cannot be scored (label the run with the text it spelled)")]
    Unscorable { recording: String, character: usize },
    #[error(transparent)]
    Unsupervised(#[from] UnsupervisedError),
    #[error(transparent)]
    Evaluate(#[from] EvaluateError),
    #[error(transparent)]
    Signal(#[from] SignalError),
    #[error(transparent)]
    Decode(#[from] DecodeError),
}

/// AUC of one recording's epochs under the final model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingAuc {
    pub recording: String,
    pub auc: f64,
}

/// What the replay got right.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnsupervisedResult {
    /// Per character, in order: 1 when the decision made online (the model fitted on the
    /// characters so far) was right.
    pub online_correct: Vec<u8>,
    /// Character accuracy of the final model's decisions with 1..=R repetitions (pooled over
    /// the recordings, up to the fewest repetitions of any).
    pub posthoc_chars_by_reps: Vec<f64>,
    /// Epoch ROC-AUC of the final model over every epoch.
    pub auc: f64,
    pub auc_by_recording: Vec<RecordingAuc>,
    pub online_text: String,
    pub posthoc_text: String,
    pub n_characters: usize,
    /// Log-likelihood of the final model (penalised), and which initialisation it came from.
    pub objective: f64,
    pub init: String,
    /// Per online refit, in order, the initialisation it kept (`Given`: the first start,
    /// `Start(1)`: the second, `Warm`: the last fit, `Random(k)`).
    pub online_inits: Vec<String>,
}

/// Where an unsupervised replay's refits start and its covariance ([`replay`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct ReplaySettings<'a> {
    /// Every refit also starts from a P300 template's scores (seen through the band-pass).
    pub template: bool,
    /// Every refit also starts from this pooled start's pattern (of the replay's band-pass,
    /// causal or zero-phase) on the epochs so far; after the template when both are given.
    pub transfer: Option<&'a PooledStart>,
    /// [`Covariance::BlockToeplitz`] over the recordings' channels instead of Ledoit–Wolf.
    pub block_toeplitz: bool,
}

/// [`evaluate_unsupervised`] with the decoder's settings for the recordings' rate and the starts
/// and covariance of `settings` (the template seen through `pre`'s band-pass, the pooled
/// start's pattern of `pre`'s causality on the first recording's channels).
pub fn replay(
    pre: &Preprocess,
    recs: &[EpochedRecording],
    settings: &ReplaySettings<'_>,
    on_character: &mut dyn FnMut(usize, usize),
) -> Result<UnsupervisedResult, ReplayError> {
    let first = recs.first().ok_or(ReplayError::Empty)?;
    let sfreq = first.epochs.sfreq();
    let mut params = UnsupervisedParams::for_sfreq(sfreq)?;
    if settings.block_toeplitz {
        params.covariance = Covariance::BlockToeplitz {
            n_channels: first.epochs.n_channels(),
        };
    }
    let template = if settings.template {
        Some(P300Template::default().matched(pre, sfreq)?)
    } else {
        None
    };
    let pooled = settings.transfer.map(|t| t.pattern(pre.causal));
    evaluate_unsupervised(&params, recs, template.as_ref(), pooled, on_character)
}

/// The pattern of labelled recordings `recs` (targets flagged; one set, e.g. a subject's runs)
/// as the unsupervised decoder's features at their rate see it: the effect size of every
/// channel and time ([`PooledPattern::from_labelled`]), for a [`PooledStart`] of other sessions.
pub fn labelled_pattern(
    recs: &[EpochedRecording],
    causal: bool,
    source: &str,
) -> Result<PooledPattern, ReplayError> {
    let first = recs.first().ok_or(ReplayError::Empty)?;
    let features = UnsupervisedParams::for_sfreq(first.epochs.sfreq())?.features;
    let mut rows = Vec::new();
    let mut y = Vec::new();
    for rec in recs {
        rows.push(features.transform(rec.epochs.data().view())?);
        y.extend(labels(&rec.epochs)?);
    }
    let views: Vec<_> = rows.iter().map(|r| r.view()).collect();
    let x = ndarray::concatenate(ndarray::Axis(0), &views).map_err(|e| {
        UnsupervisedError::InvalidPooled {
            what: format!("{source}: runs of different shapes ({e})"),
        }
    })?;
    let times = feature_times(
        features,
        first.epochs.sfreq(),
        first.epochs.tmin(),
        first.epochs.n_times(),
    );
    Ok(PooledPattern::from_labelled(
        x.view(),
        &y,
        first.epochs.ch_names(),
        &times,
        causal,
        source,
    )?)
}

/// Plays `recs` (speller recordings, every flash epoched) one after the other as one session
/// whose labels the decoder never sees; every refit starts from `template`'s scores of the
/// epochs and `pooled`'s (on the first recording's channels) when given, the warm start and
/// random initialisations ([`replay_starts`]); `on_character(k, n)` after each online decision.
pub fn evaluate_unsupervised(
    params: &UnsupervisedParams,
    recs: &[EpochedRecording],
    template: Option<&MatchedTemplate>,
    pooled: Option<&PooledPattern>,
    on_character: &mut dyn FnMut(usize, usize),
) -> Result<UnsupervisedResult, ReplayError> {
    let first = recs.first().ok_or(ReplayError::Empty)?;
    let mut constraint: Option<Constraint> = None;
    let mut codes = Vec::new();
    let mut trials = Vec::new();
    for rec in recs {
        let speller = speller_of(rec)?;
        let c = Constraint::speller(speller)?;
        match &constraint {
            Some(c0) if c0 != &c => {
                return Err(ReplayError::DifferentLayout {
                    recording: rec.name.clone(),
                    first: first.name.clone(),
                    a: c.sets().to_vec(),
                    b: c0.sets().to_vec(),
                })
            }
            Some(_) => {}
            None => constraint = Some(c),
        }
        if rec.epochs.n_epochs() != rec.n_events {
            return Err(EvaluateError::DroppedFlashes {
                recording: rec.name.clone(),
                dropped: rec.n_events - rec.epochs.n_epochs(),
                n_events: rec.n_events,
            }
            .into());
        }
        // Characters numbered on from the previous recording's.
        let first_char = trials.last().map_or(0, |&l: &usize| l + 1);
        let events = rec.epochs.events();
        codes.extend(events.iter().map(|e| e.code));
        trials.extend(
            character_of_flashes(speller, events.len())
                .into_iter()
                .map(|c| first_char + c),
        );
    }
    let constraint = constraint.expect("at least one recording");
    let parts: Vec<&Epochs> = recs.iter().map(|r| &r.epochs).collect();
    let all = Epochs::concatenate(&parts)?;
    // The decoder sees epochs, codes and characters only.
    // Epochs held as windows are read a part at a time.
    let start = template
        .map(|t| {
            EpochSource::from(&all)
                .map_scores(|chunk| chunk.outer_iter().map(|e| t.score(e)).collect())
        })
        .transpose()?
        .map(|s| s.to_vec());
    let scorer = pooled
        .map(|p| {
            let times = feature_times(params.features, all.sfreq(), all.tmin(), all.n_times());
            p.scorer(all.ch_names(), &times)
        })
        .transpose()?;
    let mut starts = Vec::new();
    if let Some(s) = &start {
        starts.push(Start::Scores(s));
    }
    if let Some(p) = &scorer {
        starts.push(Start::Pooled(p));
    }
    let r = replay_starts(
        params,
        &all,
        &codes,
        &trials,
        &constraint,
        &starts,
        on_character,
    )?;

    // Scoring: the labels, from here on only.
    let mut online_correct = Vec::new();
    let mut online_text = String::new();
    let mut posthoc_text = String::new();
    let mut all_scores = Vec::new();
    let mut all_y = Vec::new();
    let mut auc_by_recording = Vec::new();
    let mut spellers = Vec::new();
    let mut k = 0;
    for rec in recs {
        let speller = speller_of(rec)?;
        let y = labels(&rec.epochs)?;
        let events = Events::new(rec.epochs.events().to_vec());
        for (c, block) in speller.character_blocks(&events).iter().enumerate() {
            let truth = truth_of(block, &constraint).ok_or_else(|| ReplayError::Unscorable {
                recording: rec.name.clone(),
                character: c,
            })?;
            let online = &r.online[k].codes;
            online_correct.push(u8::from(online == &truth));
            online_text.push_str(&symbol(speller, online));
            k += 1;
        }
        let scores =
            EpochSource::from(&rec.epochs).map_scores(|chunk| r.model.decision_function(chunk))?;
        let s = score_speller(rec, speller, &scores)?;
        posthoc_text.push_str(&s.text);
        auc_by_recording.push(RecordingAuc {
            recording: rec.name.clone(),
            auc: roc_auc(&scores.to_vec(), &y).map_err(UnsupervisedError::from)?,
        });
        all_scores.extend(scores.iter().copied());
        all_y.extend(y);
        spellers.push(s);
    }
    let n_chars: usize = spellers.iter().map(|s| s.n_chars).sum();
    let posthoc_chars_by_reps = pooled_accuracy(&spellers);
    let (init, _) = r.model.init();
    Ok(UnsupervisedResult {
        online_correct,
        posthoc_chars_by_reps,
        auc: roc_auc(&all_scores, &all_y).map_err(UnsupervisedError::from)?,
        auc_by_recording,
        online_text,
        posthoc_text,
        n_characters: n_chars,
        objective: r.model.objective().last().copied().unwrap_or(f64::NAN),
        init: format!("{init:?}"),
        online_inits: r.online.iter().map(|o| format!("{:?}", o.init)).collect(),
    })
}

fn speller_of(rec: &EpochedRecording) -> Result<&Speller, ReplayError> {
    rec.speller.as_ref().ok_or_else(|| ReplayError::NotSpeller {
        recording: rec.name.clone(),
    })
}

/// The attended code of each constraint set in a character's events (`None` unless exactly
/// one code of each set is flagged target).
fn truth_of(block: &[oddball_signal::Event], constraint: &Constraint) -> Option<Vec<u32>> {
    constraint
        .sets()
        .iter()
        .map(|set| {
            let mut found = None;
            for e in block
                .iter()
                .filter(|e| e.target == Some(true) && set.contains(&e.code))
            {
                match found {
                    None => found = Some(e.code),
                    Some(c) if c == e.code => {}
                    Some(_) => return None,
                }
            }
            found
        })
        .collect()
}

/// The symbol at a (row code, column code) pick, `?` when there is none.
fn symbol(speller: &Speller, codes: &[u32]) -> String {
    let (mut row, mut col) = (None, None);
    for &c in codes {
        row = row.or(speller.row_of_code(c));
        col = col.or(speller.col_of_code(c));
    }
    row.zip(col)
        .and_then(|(r, c)| speller.symbol(r, c))
        .unwrap_or("?")
        .to_string()
}
