"""PyTorch architectures of the five deep baselines (imported only by their detectors' factories,
`uavcas.ids.detectors`, when they are built: torch is the optional `dl` extra).

Input: one flow = its scaled feature vector x of length F (47). Convolutional and recurrent
models read it as a 1-channel sequence of F values, the usual way these papers apply CNNs and
RNNs to flow statistics. Choices (the paper cites the references but gives no layer sizes):

- `cnn1d` (Hassler et al. 2024, \\cite{Hassler2024cyberphysical}): Conv1d(1->32,k3)-ReLU-
  MaxPool2, Conv1d(32->64,k3)-ReLU-MaxPool2, Dense 64-ReLU-Dropout 0.3, Dense C.
- `lstm` (Hassler et al. 2024): the Keras reference form, the whole feature vector as ONE time
  step (input (1, F)): LSTM(64) -> Dropout 0.2 -> Dense C.
- `convnet` (Al-Haija & Al Badawi 2022, UAV-IDS-ConvNet, \\cite{Haija22}): three conv blocks
  Conv1d(32/64/128, k3)-BatchNorm-ReLU (MaxPool2 after the second), global average pooling,
  Dense 64-ReLU-Dropout 0.5, Dense C.
- `tinyml` (Wu et al. 2024, \\cite{Wu2024tml}): a microcontroller-sized dense network,
  F -> 16 -> 8 -> C with ReLU (~1k parameters, int8-quantisable; no quantisation here).
- `cnn_bilstm` (Sinha & Manollas 2020, \\cite{Sinha2020BIRNN}): Conv1d(1->64,k3)-ReLU-MaxPool2-
  BatchNorm, BiLSTM(64 per direction) over the pooled sequence, last states of both directions
  -> Dropout 0.5 -> Dense C. (Their second BiLSTM(128) block is left out: on a 2-core CPU it
  triples the cost for no gain on 47-value inputs.)
"""

from __future__ import annotations

from .torch_estimator import DL_MISSING

try:
    import torch
except ImportError as e:  # without torch: the `dl` extra's install line, not a bare ModuleNotFoundError
    raise ImportError(DL_MISSING) from e

nn = torch.nn
F = torch.nn.functional


def _padded(x: torch.Tensor, length: int) -> torch.Tensor:
    """(batch, F) -> (batch, 1, max(F, length)): zeros appended so the pooling layers always
    have an input (a dataset may keep fewer than 4 features)."""
    return F.pad(x, (0, max(0, length - x.shape[1]))).unsqueeze(1)


class CNN1D(nn.Module):
    MIN_LENGTH = 4  # two MaxPool2 stages

    def __init__(self, n_features: int, n_classes: int) -> None:
        super().__init__()
        self.conv = nn.Sequential(
            nn.Conv1d(1, 32, 3, padding=1), nn.ReLU(), nn.MaxPool1d(2),
            nn.Conv1d(32, 64, 3, padding=1), nn.ReLU(), nn.MaxPool1d(2),
        )
        length = max(n_features, self.MIN_LENGTH) // 2 // 2
        self.head = nn.Sequential(
            nn.Flatten(), nn.Linear(64 * max(length, 1), 64), nn.ReLU(), nn.Dropout(0.3), nn.Linear(64, n_classes)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.conv(_padded(x, self.MIN_LENGTH)))


class LSTMNet(nn.Module):
    def __init__(self, n_features: int, n_classes: int) -> None:
        super().__init__()
        self.lstm = nn.LSTM(n_features, 64, batch_first=True)
        self.head = nn.Sequential(nn.Dropout(0.2), nn.Linear(64, n_classes))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        _, (h, _) = self.lstm(x.unsqueeze(1))  # (batch, 1 step, F)
        return self.head(h[-1])


class ConvNet(nn.Module):
    MIN_LENGTH = 2  # one MaxPool2 stage

    def __init__(self, n_features: int, n_classes: int) -> None:
        super().__init__()

        def block(i: int, o: int) -> list[nn.Module]:
            return [nn.Conv1d(i, o, 3, padding=1), nn.BatchNorm1d(o), nn.ReLU()]

        self.conv = nn.Sequential(*block(1, 32), *block(32, 64), nn.MaxPool1d(2), *block(64, 128))
        self.head = nn.Sequential(nn.Linear(128, 64), nn.ReLU(), nn.Dropout(0.5), nn.Linear(64, n_classes))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.conv(_padded(x, self.MIN_LENGTH)).mean(-1))


class TinyML(nn.Module):
    def __init__(self, n_features: int, n_classes: int) -> None:
        super().__init__()
        self.net = nn.Sequential(nn.Linear(n_features, 16), nn.ReLU(), nn.Linear(16, 8), nn.ReLU(),
                                 nn.Linear(8, n_classes))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.net(x)


class CNNBiLSTM(nn.Module):
    MIN_LENGTH = 2  # one MaxPool2 stage

    def __init__(self, n_features: int, n_classes: int) -> None:
        super().__init__()
        self.conv = nn.Sequential(nn.Conv1d(1, 64, 3, padding=1), nn.ReLU(), nn.MaxPool1d(2), nn.BatchNorm1d(64))
        self.lstm = nn.LSTM(64, 64, batch_first=True, bidirectional=True)
        self.head = nn.Sequential(nn.Dropout(0.5), nn.Linear(128, n_classes))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        z = self.conv(_padded(x, self.MIN_LENGTH)).transpose(1, 2)  # (batch, steps, 64 channels)
        _, (h, _) = self.lstm(z)
        return self.head(torch.cat([h[-2], h[-1]], dim=1))

